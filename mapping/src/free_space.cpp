#include "dynamap/mapping/free_space.hpp"

#include <algorithm>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace dynamap {

namespace {

constexpr float kFreeSpaceNoReading = 1e3f;

cv::Mat halfResolution(const cv::Mat& depth_m) {
  cv::Mat half;
  cv::resize(depth_m, half, cv::Size(depth_m.cols / 2, depth_m.rows / 2), 0, 0, cv::INTER_NEAREST);
  return half;
}

/// Drops specks: connected regions smaller than min_area pixels after an opening, except the
/// (unopened) regions that touch `near_mover` (may be empty).
void keepLargeRegions(cv::Mat& mask, int min_area, const cv::Mat& near_mover) {
  cv::Mat opened;
  cv::morphologyEx(mask, opened, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(opened, labels, stats, centroids, 8, CV_32S);
  for (int i = 1; i < n; ++i) {
    if (stats.at<int>(i, cv::CC_STAT_AREA) < min_area) opened.setTo(0, labels == i);
  }
  if (!near_mover.empty() && cv::countNonZero(near_mover) > 0) {
    const int m = cv::connectedComponents(mask, labels, 8, CV_32S);
    std::vector<bool> touches(static_cast<std::size_t>(m), false);
    for (int v = 0; v < mask.rows; ++v) {
      const int* l = labels.ptr<int>(v);
      const uchar* near = near_mover.ptr<uchar>(v);
      for (int u = 0; u < mask.cols; ++u) {
        if (l[u] > 0 && near[u] != 0) touches[static_cast<std::size_t>(l[u])] = true;
      }
    }
    for (int v = 0; v < mask.rows; ++v) {
      const int* l = labels.ptr<int>(v);
      uchar* out = opened.ptr<uchar>(v);
      for (int u = 0; u < mask.cols; ++u) {
        if (l[u] > 0 && touches[static_cast<std::size_t>(l[u])]) out[u] = 255;
      }
    }
  }
  mask = opened;
}

void markViolations(const PinholeCamera& camera, const cv::Mat& half_depth_m,
                    const Eigen::Isometry3d& T_W_C, const FreeSpaceView& ref,
                    const FreeSpaceOptions& options, cv::Mat& flagged) {
  const Eigen::Matrix4d T = (ref.T_W_C.inverse() * T_W_C).matrix();  // this camera -> ref
  const double fx = camera.fx, fy = camera.fy, cx = camera.cx, cy = camera.cy;
  const int w = ref.near_half_m.cols, h = ref.near_half_m.rows;
  for (int v = 0; v < half_depth_m.rows; ++v) {
    const float* row = half_depth_m.ptr<float>(v);
    uchar* out = flagged.ptr<uchar>(v);
    const double y_n = (2.0 * v - cy) / fy;
    for (int u = 0; u < half_depth_m.cols; ++u) {
      const double z = row[u];
      if (z <= 0.0 || z > options.max_depth_m || out[u] != 0) continue;
      const double x = (2.0 * u - cx) / fx * z, y = y_n * z;
      const double xr = T(0, 0) * x + T(0, 1) * y + T(0, 2) * z + T(0, 3);
      const double yr = T(1, 0) * x + T(1, 1) * y + T(1, 2) * z + T(1, 3);
      const double zr = T(2, 0) * x + T(2, 1) * y + T(2, 2) * z + T(2, 3);
      if (zr < 0.1) continue;
      const int ur = cvRound(0.5 * (fx * xr / zr + cx)), vr = cvRound(0.5 * (fy * yr / zr + cy));
      if (ur < 0 || vr < 0 || ur >= w || vr >= h) continue;
      const double seen = ref.near_half_m.at<float>(vr, ur);
      if (seen <= 0.0) continue;
      if (zr < seen - options.margin_m - options.margin_per_m2 * seen * seen) out[u] = 255;
    }
  }
}

}  // namespace

FreeSpaceView makeFreeSpaceView(const cv::Mat& depth_m, const Eigen::Isometry3d& T_W_C) {
  FreeSpaceView view;
  view.T_W_C = T_W_C;
  if (depth_m.empty()) return view;
  cv::Mat d = halfResolution(depth_m);
  cv::Mat invalid = d <= 0.f;
  d.setTo(kFreeSpaceNoReading, invalid);
  cv::erode(d, d, cv::getStructuringElement(cv::MORPH_RECT, {5, 5}));  // nearest in the window
  d.setTo(0.f, d >= kFreeSpaceNoReading);
  view.near_half_m = d;
  return view;
}

cv::Mat freeSpaceViolations(const PinholeCamera& camera, const cv::Mat& depth_m,
                            const Eigen::Isometry3d& T_W_C,
                            const std::vector<const FreeSpaceView*>& others,
                            const FreeSpaceOptions& options, const cv::Mat& dynamic_mask) {
  if (depth_m.empty()) return {};
  const cv::Mat half = halfResolution(depth_m);
  cv::Mat flagged = cv::Mat::zeros(half.size(), CV_8UC1);
  for (const FreeSpaceView* other : others) {
    if (other != nullptr && !other->near_half_m.empty()) {
      markViolations(camera, half, T_W_C, *other, options, flagged);
    }
  }
  cv::Mat near_mover;
  if (!dynamic_mask.empty() && options.fringe_px > 0 && dynamic_mask.size() == depth_m.size()) {
    cv::resize(dynamic_mask == 255, near_mover, half.size(), 0, 0, cv::INTER_NEAREST);
    const int r = std::max(1, options.fringe_px / 2);
    cv::dilate(near_mover, near_mover,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1}));
  }
  keepLargeRegions(flagged, std::max(1, options.min_area_px / 4), near_mover);
  cv::Mat full;
  cv::resize(flagged, full, depth_m.size(), 0, 0, cv::INTER_NEAREST);
  return full;
}

}  // namespace dynamap
