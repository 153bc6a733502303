#include "dynamap/core/tracking/lk_tracker.hpp"

#include <algorithm>
#include <future>

#include <opencv2/video/tracking.hpp>

#ifdef DYNAMAP_HAVE_FAST_PATHS
#include "dynamap/fast_paths/own_pyr_lk.hpp"
#endif

namespace dynamap {
namespace {

/// OpenCV's pyramidal LK with initial flow, or the fast path's (core/fast_paths) where it runs.
void pyramidalLk(const LkPyramid& from, const LkPyramid& to, const std::vector<cv::Point2f>& px,
                 std::vector<cv::Point2f>& tracked, std::vector<std::uint8_t>& status,
                 cv::Size window, int max_level, const cv::TermCriteria& criteria) {
#ifdef DYNAMAP_HAVE_FAST_PATHS
  if (lk::ownPyrLkUsable(window)) {
    lk::ownPyrLk(from, to, px, tracked, status, window, max_level, criteria);
    return;
  }
#endif
  cv::calcOpticalFlowPyrLK(from, to, px, tracked, status, cv::noArray(), window, max_level,
                           criteria, cv::OPTFLOW_USE_INITIAL_FLOW);
}

}  // namespace

LkTracker::LkTracker(const TrackerConfig& config)
    : window_(config.lk_window_px, config.lk_window_px),
      max_level_(std::max(0, config.lk_levels - 1)),
      max_iterations_(config.lk_max_iterations),
      fb_threshold_px_(config.lk_fb_threshold_px),
      threads_(config.lk_threads) {}

LkPyramid LkTracker::buildPyramid(const cv::Mat& gray) const {
  LkPyramid pyramid;
  cv::buildOpticalFlowPyramid(gray, pyramid, window_, max_level_, true);
  return pyramid;
}

void LkTracker::track(const LkPyramid& prev, const LkPyramid& cur,
                      const std::vector<cv::Point2f>& prev_px, std::vector<cv::Point2f>& cur_px,
                      std::vector<std::uint8_t>& ok, int backward_levels) const {
  ok.assign(prev_px.size(), 0);
  const int back = backward_levels > 0 ? std::min(max_level_, backward_levels - 1) : max_level_;
  if (prev_px.empty() || prev.empty() || cur.empty()) return;
  // Each point is tracked on its own, so the points split over threads give the same result.
  const std::size_t n = prev_px.size();
  if (threads_ < 2 || n < kMinPointsPerThread * 2) {
    trackRange(prev, cur, prev_px, cur_px, ok, back, 0, n);
    return;
  }
  const std::size_t half = n / 2;
  auto first = std::async(std::launch::async,
                          [&] { trackRange(prev, cur, prev_px, cur_px, ok, back, 0, half); });
  trackRange(prev, cur, prev_px, cur_px, ok, back, half, n);
  first.get();
}

void LkTracker::trackRange(const LkPyramid& prev, const LkPyramid& cur,
                           const std::vector<cv::Point2f>& all_prev_px,
                           std::vector<cv::Point2f>& all_cur_px, std::vector<std::uint8_t>& all_ok,
                           int backward_max_level, std::size_t begin, std::size_t end) const {
  const auto b = static_cast<std::ptrdiff_t>(begin), e = static_cast<std::ptrdiff_t>(end);
  const std::vector<cv::Point2f> prev_px(all_prev_px.begin() + b, all_prev_px.begin() + e);
  std::vector<cv::Point2f> cur_px(all_cur_px.begin() + b, all_cur_px.begin() + e);
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, max_iterations_,
                                  0.01);
  std::vector<std::uint8_t> fwd_status, bwd_status;
  // No error output: OpenCV then skips a last (scalar) pass over each window. That pass only
  // also fails points that end a window or more outside the image, which the bounds and
  // forward-backward checks below fail anyway.
  pyramidalLk(prev, cur, prev_px, cur_px, fwd_status, window_, max_level_, criteria);
  // The backward pass only for the points that passed forward inside the image: every point is
  // tracked on its own, so the others' results do not change.
  const cv::Size size = cur.front().size();
  const auto inside = [&](const cv::Point2f& p) {
    return !(p.x < 0.f || p.y < 0.f || p.x > static_cast<float>(size.width - 1) ||
             p.y > static_cast<float>(size.height - 1));
  };
  std::vector<std::size_t> back_of;
  std::vector<cv::Point2f> back_from, back_px;
  for (std::size_t i = 0; i < prev_px.size(); ++i) {
    all_cur_px[begin + i] = cur_px[i];
    if (!fwd_status[i] || !inside(cur_px[i])) continue;
    back_of.push_back(i);
    back_from.push_back(cur_px[i]);
    back_px.push_back(prev_px[i]);
  }
  if (back_of.empty()) return;
  pyramidalLk(cur, prev, back_from, back_px, bwd_status, window_, backward_max_level, criteria);
  const double fb2 = fb_threshold_px_ * fb_threshold_px_;
  for (std::size_t j = 0; j < back_of.size(); ++j) {
    const std::size_t i = back_of[j];
    const cv::Point2f d = back_px[j] - prev_px[i];
    if (bwd_status[j] && !(d.dot(d) > fb2)) all_ok[begin + i] = 1;
  }
}

}  // namespace dynamap
