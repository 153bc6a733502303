#include "dynamap/mapping/mask_lookahead.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dynamap/core/rounding.hpp"

namespace dynamap {
namespace {
constexpr double kMaxMoveM = 0.3;    ///< 9 m/s at 30 frames/s over one frame
constexpr double kMaxTurnRad = 0.5;  ///< about 29 degrees
}  // namespace

cv::Mat maskSeenLater(const PinholeCamera& camera, const cv::Mat& depth_m,
                      const Eigen::Isometry3d& T_W_K, const cv::Mat& later_depth_m,
                      const Eigen::Isometry3d& T_W_L, const cv::Mat& later_mask,
                      double occluder_margin_m) {
  cv::Mat out = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  if (depth_m.empty() || later_mask.empty() || later_mask.size() != later_depth_m.size() ||
      cv::countNonZero(later_mask) == 0) {
    return out;
  }
  const Eigen::Isometry3d T_L_K_d = T_W_L.inverse() * T_W_K;
  if (T_L_K_d.translation().norm() >= kMaxMoveM ||
      Eigen::AngleAxisd(T_L_K_d.rotation()).angle() >= kMaxTurnRad) {
    return out;  // another map's pose (a restart after a loss), not a frame or two later
  }
  const Eigen::Isometry3f T_L_K = T_L_K_d.cast<float>();
  const Eigen::Matrix3f R = T_L_K.linear();
  const Eigen::Vector3f t = T_L_K.translation();
  const auto fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const auto cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  const auto margin = static_cast<float>(occluder_margin_m);
  const int w = later_mask.cols, h = later_mask.rows;
  // Every 2nd pixel of every 2nd row, marking its 2 x 2 block: a quarter of the projections.
  constexpr int kStride = 2;
  std::vector<float> x_n(static_cast<std::size_t>(depth_m.cols));
  for (int u = 0; u < depth_m.cols; u += kStride) {
    x_n[static_cast<std::size_t>(u)] = (static_cast<float>(u) - cx) / fx;
  }
  for (int v = 0; v < depth_m.rows; v += kStride) {
    const float* z_row = depth_m.ptr<float>(v);
    const float y_n = (static_cast<float>(v) - cy) / fy;
    for (int u = 0; u < depth_m.cols; u += kStride) {
      const float z = z_row[u];
      if (!(z > 0.0f)) continue;
      const Eigen::Vector3f p =
          R * Eigen::Vector3f(x_n[static_cast<std::size_t>(u)] * z, y_n * z, z) + t;
      if (p.z() <= 0.1f) continue;
      const int ul = static_cast<int>(roundHalfAway(fx * p.x() / p.z() + cx));
      const int vl = static_cast<int>(roundHalfAway(fy * p.y() / p.z() + cy));
      if (ul < 0 || vl < 0 || ul >= w || vl >= h) continue;
      if (later_mask.at<std::uint8_t>(vl, ul) == 0) continue;
      const float seen = later_depth_m.at<float>(vl, ul);
      if (seen > 0.0f && seen >= p.z() - margin) {
        for (int y = v; y < std::min(v + kStride, out.rows); ++y) {
          std::uint8_t* row = out.ptr<std::uint8_t>(y);
          for (int x = u; x < std::min(u + kStride, out.cols); ++x) row[x] = 255;
        }
      }
    }
  }
  return out;
}

cv::Mat marginNotBehind(const cv::Mat& mask, const cv::Mat& depth_m, int radius_px,
                        double behind_m) {
  if (behind_m <= 0.0 || radius_px <= 0 || mask.empty() || depth_m.size() != mask.size()) {
    return mask;
  }
  // The mask's core (what the margin was grown from) and the farthest depth of the core within
  // the margin of each pixel; pixels with no core that near (a sliver a later frame's mask
  // added) stay as they are.
  // Only the mask's bounding box grown by the radius is worked on: every pixel of the mask has
  // its whole disc there, and outside the mask nothing changes.
  cv::Mat out = mask.clone();
  const cv::Rect bound = cv::boundingRect(mask);
  if (bound.area() == 0) return out;
  const cv::Rect roi = cv::Rect(bound.x - radius_px, bound.y - radius_px,
                                bound.width + 2 * radius_px, bound.height + 2 * radius_px) &
                       cv::Rect(0, 0, mask.cols, mask.rows);
  const int k = 2 * radius_px + 1;
  const cv::Mat disc = cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k});
  cv::Mat core;
  cv::erode(mask(roi), core, disc);
  cv::Mat core_depth = cv::Mat::zeros(roi.size(), CV_32FC1);
  depth_m(roi).copyTo(core_depth, core);
  cv::Mat farthest;
  cv::dilate(core_depth, farthest, disc);
  out(roi).setTo(0, (depth_m(roi) > farthest + behind_m) & (farthest > 0.f));
  return out;
}

}  // namespace dynamap
