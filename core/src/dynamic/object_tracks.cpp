#include "dynamap/core/dynamic/object_tracks.hpp"

#include <algorithm>
#include <cmath>

#include "dynamap/core/dynamic/depth_check.hpp"

namespace dynamap {
namespace {

/// The anchor of point `id` in `anchors` (sorted by id), or null.
const PointAnchor* findAnchor(const std::vector<PointAnchor>& anchors, std::uint64_t id) {
  const auto it = std::lower_bound(anchors.begin(), anchors.end(), id,
                                   [](const PointAnchor& a, std::uint64_t v) { return a.id < v; });
  return it != anchors.end() && it->id == id ? &*it : nullptr;
}

}  // namespace

AnchorCheck checkAnchors(const std::vector<PointAnchor>& anchors,
                         const std::vector<PointSample>& now, const cv::Matx44d& T_W_C,
                         const cv::Vec4d& K) {
  AnchorCheck out;
  out.checked = true;
  const cv::Matx44d T_C_W = T_W_C.inv(cv::DECOMP_SVD);
  std::vector<double> dist, dz;
  for (const auto& s : now) {
    if (s.depth_m <= 0.f) continue;
    const double z = s.depth_m;
    const cv::Vec4d p_C((s.px.x - K[2]) / K[0] * z, (s.px.y - K[3]) / K[1] * z, z, 1.0);
    const cv::Vec4d p_W = T_W_C * p_C;
    const PointAnchor here{s.id, cv::Vec3d(p_W[0], p_W[1], p_W[2])};
    out.fresh.push_back(here);
    const PointAnchor* anchor = findAnchor(anchors, s.id);
    if (anchor == nullptr) {
      out.kept.push_back(here);
      continue;
    }
    out.kept.push_back(*anchor);
    const cv::Vec4d q = T_C_W * cv::Vec4d(anchor->p_W[0], anchor->p_W[1], anchor->p_W[2], 1.0);
    if (q[2] <= 0.05) continue;
    const cv::Point2f uv(static_cast<float>(K[0] * q[0] / q[2] + K[2]),
                         static_cast<float>(K[1] * q[1] / q[2] + K[3]));
    dist.push_back(cv::norm(uv - s.px));
    dz.push_back(s.depth_m - q[2]);
  }
  const auto by_id = [](const PointAnchor& a, const PointAnchor& b) { return a.id < b.id; };
  std::sort(out.kept.begin(), out.kept.end(), by_id);
  std::sort(out.fresh.begin(), out.fresh.end(), by_id);
  out.points = static_cast<int>(dist.size());
  if (!dist.empty()) {
    const auto mid = dist.begin() + static_cast<std::ptrdiff_t>(dist.size() / 2);
    std::nth_element(dist.begin(), mid, dist.end());
    out.median_px = *mid;
    const auto mid_z = dz.begin() + static_cast<std::ptrdiff_t>(dz.size() / 2);
    std::nth_element(dz.begin(), mid_z, dz.end());
    out.median_dz_m = *mid_z;
  }
  return out;
}

std::vector<cv::Vec3f> sampleSurface(const cv::Mat& region, const cv::Mat& depth_m,
                                     const cv::Matx44d& T_W_C, const cv::Vec4d& K, int stride_px) {
  std::vector<cv::Vec3f> out;
  if (region.empty() || region.size() != depth_m.size()) return out;
  const int step = std::max(1, stride_px);
  for (int v = step / 2; v < region.rows; v += step) {
    const std::uint8_t* in = region.ptr<std::uint8_t>(v);
    for (int u = step / 2; u < region.cols; u += step) {
      if (in[u] == 0) continue;
      const double z = interiorDepth(depth_m, u, v);
      if (!(z > 0.0)) continue;
      const cv::Vec4d p = T_W_C * cv::Vec4d((u - K[2]) / K[0] * z, (v - K[3]) / K[1] * z, z, 1.0);
      out.emplace_back(static_cast<float>(p[0]), static_cast<float>(p[1]),
                       static_cast<float>(p[2]));
    }
  }
  return out;
}

void checkSurface(const std::vector<cv::Vec3f>& surface_W, const cv::Mat& region,
                  const cv::Mat& depth_m, const cv::Matx44d& T_W_C, const cv::Vec4d& K,
                  double max_dz_m, AnchorCheck* out) {
  out->surface_points = 0;
  out->surface_dz_m = 0.0;
  if (surface_W.empty() || region.empty() || region.size() != depth_m.size()) return;
  const cv::Matx44d T_C_W = T_W_C.inv(cv::DECOMP_SVD);
  std::vector<double> dz;
  dz.reserve(surface_W.size());
  for (const cv::Vec3f& p : surface_W) {
    const cv::Vec4d q = T_C_W * cv::Vec4d(p[0], p[1], p[2], 1.0);
    if (q[2] <= 0.1) continue;
    const int u = cvRound(K[0] * q[0] / q[2] + K[2]), v = cvRound(K[1] * q[1] / q[2] + K[3]);
    if (u < 0 || v < 0 || u >= region.cols || v >= region.rows) continue;
    if (region.at<std::uint8_t>(v, u) == 0) continue;
    const double z = interiorDepth(depth_m, u, v);
    if (z > 0.0 && std::abs(z - q[2]) <= max_dz_m) dz.push_back(z - q[2]);
  }
  if (dz.empty()) return;
  const auto mid = dz.begin() + static_cast<std::ptrdiff_t>(dz.size() / 2);
  std::nth_element(dz.begin(), mid, dz.end());
  out->surface_points = static_cast<int>(dz.size());
  out->surface_dz_m = *mid;
}

bool medianFlowIn(const cv::Rect2f& box, const std::vector<cv::Point2f>& prev_px,
                  const std::vector<cv::Point2f>& cur_px, cv::Point2f* flow, int min_points) {
  std::vector<float> dx, dy;
  const std::size_t n = std::min(prev_px.size(), cur_px.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (!box.contains(prev_px[i])) continue;
    dx.push_back(cur_px[i].x - prev_px[i].x);
    dy.push_back(cur_px[i].y - prev_px[i].y);
  }
  if (static_cast<int>(dx.size()) < std::max(1, min_points)) return false;
  const auto mid = static_cast<std::ptrdiff_t>(dx.size() / 2);
  std::nth_element(dx.begin(), dx.begin() + mid, dx.end());
  std::nth_element(dy.begin(), dy.begin() + mid, dy.end());
  *flow = cv::Point2f(dx[static_cast<std::size_t>(mid)], dy[static_cast<std::size_t>(mid)]);
  return true;
}

std::vector<int> associateDetections(const std::vector<Detection>& detections,
                                     const std::vector<ObjectTrack>& tracks, float min_iou) {
  std::vector<int> of_detection(detections.size(), -1);
  for (std::size_t d = 0; d < detections.size(); ++d) {
    float best = min_iou;
    for (std::size_t t = 0; t < tracks.size(); ++t) {
      if (tracks[t].class_id != detections[d].class_id) continue;
      const float o = iou(tracks[t].box, detections[d].box);
      if (o > best) best = o, of_detection[d] = static_cast<int>(t);
    }
  }
  return of_detection;
}

int trackSharingPoints(const std::vector<std::uint64_t>& ids,
                       const std::vector<ObjectTrack>& tracks, int class_id, int min_shared) {
  int best = -1, best_shared = std::max(1, min_shared) - 1;
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    if (tracks[t].class_id != class_id) continue;
    int shared = 0;
    for (const std::uint64_t id : ids) shared += findAnchor(tracks[t].anchors, id) != nullptr;
    if (shared > best_shared) best = static_cast<int>(t), best_shared = shared;
  }
  return best;
}

}  // namespace dynamap
