#include "dynamap/mapping/static_points.hpp"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "dynamap/mapping/map_backend.hpp"

namespace dynamap {
namespace {

// True when a valid 4-neighbour's depth differs by more than `threshold` (a mixed pixel).
bool isDepthEdge(const cv::Mat& depth, int r, int c, float z, float threshold) {
  const int dr[4] = {-1, 1, 0, 0};
  const int dc[4] = {0, 0, -1, 1};
  for (int k = 0; k < 4; ++k) {
    const int rr = r + dr[k];
    const int cc = c + dc[k];
    if (rr < 0 || cc < 0 || rr >= depth.rows || cc >= depth.cols) continue;
    const float zn = depth.at<float>(rr, cc);
    if (zn > 0.0f && std::fabs(zn - z) > threshold) return true;
  }
  return false;
}

}  // namespace

void backProjectDepth(const PinholeCamera& camera, const cv::Mat& bgr, const cv::Mat& depth_m,
                      int stride, std::vector<Eigen::Vector3f>* points_C,
                      std::vector<std::array<std::uint8_t, 3>>* colors) {
  points_C->clear();
  colors->clear();
  const int step = std::max(1, stride);
  const bool has_colour = !bgr.empty() && bgr.size() == depth_m.size() && bgr.type() == CV_8UC3;
  points_C->reserve(static_cast<std::size_t>(depth_m.total() / (step * step)));
  colors->reserve(points_C->capacity());
  for (int r = 0; r < depth_m.rows; r += step) {
    const float* row = depth_m.ptr<float>(r);
    for (int c = 0; c < depth_m.cols; c += step) {
      const float z = row[c];
      if (!(z > 0.0f)) continue;
      points_C->emplace_back(camera.backProject(c, r, z).cast<float>());
      if (has_colour) {
        const cv::Vec3b p = bgr.at<cv::Vec3b>(r, c);
        colors->push_back({p[2], p[1], p[0]});
      } else {
        colors->push_back({128, 128, 128});
      }
    }
  }
}

cv::Mat dilatedMask(const cv::Mat& dynamic_mask, int radius_px) {
  cv::Mat moving = dynamic_mask == 255;
  if (radius_px <= 0) return moving;
  const cv::Mat kernel =
      cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius_px + 1, 2 * radius_px + 1));
  cv::Mat dilated;
  cv::dilate(moving, dilated, kernel);
  return dilated;
}

cv::Mat staticDepth(const cv::Mat& depth_m, const cv::Mat& dynamic_mask,
                    const StaticPointsOptions& options) {
  if (depth_m.type() != CV_32FC1) throw MappingError("extractStaticPoints: depth must be CV_32FC1");
  const bool has_mask = !dynamic_mask.empty();
  if (has_mask && (dynamic_mask.type() != CV_8UC1 || dynamic_mask.size() != depth_m.size())) {
    throw MappingError("extractStaticPoints: dynamic mask must be CV_8UC1 of the depth size");
  }
  const cv::Mat moving = has_mask ? dilatedMask(dynamic_mask, options.mask_dilation_px) : cv::Mat();
  const auto z_min = static_cast<float>(options.depth_min_m);
  const auto z_max = static_cast<float>(options.depth_max_m);
  const auto edge = static_cast<float>(options.depth_edge_threshold_m);

  cv::Mat out = cv::Mat::zeros(depth_m.size(), CV_32FC1);
  for (int r = 0; r < depth_m.rows; ++r) {
    const float* in = depth_m.ptr<float>(r);
    float* dst = out.ptr<float>(r);
    const std::uint8_t* m = has_mask ? moving.ptr<std::uint8_t>(r) : nullptr;
    for (int c = 0; c < depth_m.cols; ++c) {
      const float z = in[c];
      if (!(z >= z_min && z <= z_max)) continue;
      if (m != nullptr && m[c] != 0) continue;
      if (edge > 0.0f && isDepthEdge(depth_m, r, c, z, edge)) continue;
      dst[c] = z;
    }
  }
  return out;
}

KeyframeView keyframeView(std::uint64_t id, double timestamp_s, const Eigen::Isometry3d& T_W_C,
                          const PinholeCamera& camera, const cv::Mat& bgr, const StaticPoints& sp) {
  KeyframeView view;
  view.id = id;
  view.timestamp_s = timestamp_s;
  view.T_W_C = T_W_C;
  view.camera = &camera;
  view.bgr = &bgr;
  view.static_depth_m = &sp.static_depth_m;
  view.points_C = &sp.points_C;
  view.colors = &sp.colors;
  return view;
}

StaticPoints extractStaticPoints(const PinholeCamera& camera, const cv::Mat& bgr,
                                 const cv::Mat& depth_m, const cv::Mat& dynamic_mask,
                                 const StaticPointsOptions& options) {
  StaticPoints out;
  out.static_depth_m = staticDepth(depth_m, dynamic_mask, options);
  backProjectDepth(camera, bgr, out.static_depth_m, options.stride, &out.points_C, &out.colors);
  return out;
}

}  // namespace dynamap
