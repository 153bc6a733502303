#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/tracker_config.hpp"

namespace dynamap {

/// An image pyramid for LK, built once per frame and reused as "previous" by the next frame.
using LkPyramid = std::vector<cv::Mat>;

/// Pyramidal Lucas-Kanade with a forward-backward consistency check. Stateless, thread-safe.
class LkTracker {
 public:
  explicit LkTracker(const TrackerConfig& config);

  LkPyramid buildPyramid(const cv::Mat& gray) const;

  /// Tracks `prev_px` from `prev` into `cur`. `cur_px` holds the initial guesses on entry (same
  /// size as prev_px) and the tracked positions on exit; ok[i] = 1 when the track passed the
  /// forward-backward check and stays inside the image. backward_levels > 0: the backward
  /// (check) pass, which starts from the point's own position, uses that many levels only.
  void track(const LkPyramid& prev, const LkPyramid& cur, const std::vector<cv::Point2f>& prev_px,
             std::vector<cv::Point2f>& cur_px, std::vector<std::uint8_t>& ok,
             int backward_levels = 0) const;

 private:
  static constexpr std::size_t kMinPointsPerThread = 32;
  /// Tracks points [begin, end) of the vectors (ok and cur_px written there only).
  void trackRange(const LkPyramid& prev, const LkPyramid& cur,
                  const std::vector<cv::Point2f>& prev_px, std::vector<cv::Point2f>& cur_px,
                  std::vector<std::uint8_t>& ok, int backward_max_level, std::size_t begin,
                  std::size_t end) const;

  cv::Size window_;
  int max_level_;
  int max_iterations_;
  double fb_threshold_px_;
  int threads_;
};

}  // namespace dynamap
