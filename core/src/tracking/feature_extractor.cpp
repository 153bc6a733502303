#include "dynamap/core/tracking/feature_extractor.hpp"

#include <algorithm>

namespace dynamap {

GridOrbExtractor::GridOrbExtractor(const TrackerConfig& config)
    : orb_(cv::ORB::create(config.orb_features, static_cast<float>(config.orb_scale_factor),
                           config.orb_levels, 19, 0, 2, cv::ORB::HARRIS_SCORE, 31,
                           config.orb_fast_threshold)),
      cell_px_(std::max(1, config.grid_cell_px)) {}

OrbFeatures GridOrbExtractor::extract(const cv::Mat& gray, const cv::Mat& allowed,
                                      const std::vector<cv::Point2f>& occupied) const {
  OrbFeatures out;
  if (gray.empty()) return out;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  orb_->detectAndCompute(gray, allowed, keypoints, descriptors);
  if (keypoints.empty()) return out;

  const int cols = (gray.cols + cell_px_ - 1) / cell_px_;
  const int rows = (gray.rows + cell_px_ - 1) / cell_px_;
  auto cellOf = [&](const cv::Point2f& p) {
    const int cx = std::clamp(static_cast<int>(p.x) / cell_px_, 0, cols - 1);
    const int cy = std::clamp(static_cast<int>(p.y) / cell_px_, 0, rows - 1);
    return cy * cols + cx;
  };
  std::vector<int> best(static_cast<std::size_t>(cols * rows), -1);
  std::vector<char> taken(best.size(), 0);
  for (const auto& p : occupied) taken[static_cast<std::size_t>(cellOf(p))] = 1;
  for (int i = 0; i < static_cast<int>(keypoints.size()); ++i) {
    const auto cell = static_cast<std::size_t>(cellOf(keypoints[static_cast<std::size_t>(i)].pt));
    if (taken[cell]) continue;
    if (best[cell] < 0 || keypoints[static_cast<std::size_t>(i)].response >
                              keypoints[static_cast<std::size_t>(best[cell])].response) {
      best[cell] = i;
    }
  }
  for (int idx : best) {
    if (idx < 0) continue;
    out.keypoints.push_back(keypoints[static_cast<std::size_t>(idx)]);
    out.descriptors.push_back(descriptors.row(idx));
  }
  return out;
}

}  // namespace dynamap
