// Tracker::Impl's motion probes (TrackerConfig::motion_probes): LK points, not landmarks, handed
// to the motion filter with the landmark matches so that it sees the whole image every frame.

#include <algorithm>

#include <opencv2/imgproc.hpp>

#include "dynamap/core/tracking/tracker_impl.hpp"

namespace dynamap {

// Probes follow the flow of the frame (seeded by the median landmark flow) and are appended
// after the landmark matches; they only inform the motion filter.
void Tracker::Impl::trackProbes(const LkPyramid& cur, FeatureMatches& matches) {
  if (!filter_ || probes_.empty() || prev_pyramid_.empty()) {
    probes_.clear();
    probe_ids_.clear();
    return;
  }
  cv::Point2f flow(0.f, 0.f);
  if (!matches.cur_px.empty()) {
    std::vector<float> dx, dy;
    for (std::size_t i = 0; i < matches.cur_px.size(); ++i) {
      dx.push_back(matches.cur_px[i].x - matches.prev_px[i].x);
      dy.push_back(matches.cur_px[i].y - matches.prev_px[i].y);
    }
    const auto mid = static_cast<std::ptrdiff_t>(dx.size() / 2);
    std::nth_element(dx.begin(), dx.begin() + mid, dx.end());
    std::nth_element(dy.begin(), dy.begin() + mid, dy.end());
    flow = cv::Point2f(dx[static_cast<std::size_t>(mid)], dy[static_cast<std::size_t>(mid)]);
  }
  std::vector<cv::Point2f> cur_px(probes_.size());
  for (std::size_t i = 0; i < probes_.size(); ++i) cur_px[i] = probes_[i] + flow;
  std::vector<std::uint8_t> ok;
  lk_.track(prev_pyramid_, cur, probes_, cur_px, ok, config_.motion_probe_backward_levels);
  std::vector<cv::Point2f> kept;
  std::vector<std::uint64_t> kept_ids;
  kept.reserve(probes_.size());
  for (std::size_t i = 0; i < probes_.size(); ++i) {
    if (!ok[i]) continue;
    matches.prev_px.push_back(probes_[i]);
    matches.cur_px.push_back(cur_px[i]);
    matches.ids.push_back(probe_ids_[i]);
    kept.push_back(cur_px[i]);
    kept_ids.push_back(probe_ids_[i]);
  }
  probes_.swap(kept);
  probe_ids_.swap(kept_ids);
}

// Tops the probes up from the current frame (which is the next frame's previous one).
void Tracker::Impl::refillProbes(const cv::Mat& gray) {
  const int wanted = filter_ ? config_.motion_probes : 0;
  if (wanted <= 0) {
    probes_.clear();
    probe_ids_.clear();
    return;
  }
  if (static_cast<int>(probes_.size()) >= wanted * 7 / 10) return;
  ScopedStageTimer timer(timings_, "probes");
  const int spacing = std::max(1, config_.motion_probe_min_distance_px);
  cv::Mat allowed(gray.size(), CV_8UC1, cv::Scalar(255));
  for (const auto& p : probes_) cv::circle(allowed, p, spacing, cv::Scalar(0), -1);
  std::vector<cv::Point2f> fresh;
  cv::goodFeaturesToTrack(gray, fresh, wanted - static_cast<int>(probes_.size()), 0.01, spacing,
                          allowed);
  probes_.insert(probes_.end(), fresh.begin(), fresh.end());
  for (std::size_t i = 0; i < fresh.size(); ++i)
    probe_ids_.push_back(kProbeIdBit | next_probe_id_++);
}

}  // namespace dynamap
