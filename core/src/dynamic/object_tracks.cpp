#include "dynamap/core/dynamic/object_tracks.hpp"

#include <algorithm>

namespace dynamap {

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

}  // namespace dynamap
