#include "dynamap/core/tracking/feature_extractor.hpp"

#include <algorithm>

namespace dynamap {
namespace {

/// ORB's orientation: angle (degrees) of the intensity centroid in a radius-15 disc.
float intensityCentroidAngle(const cv::Mat& gray, const cv::Point2f& pt) {
  constexpr int kRadius = 15;
  const int cx = cvRound(pt.x), cy = cvRound(pt.y);
  double m01 = 0.0, m10 = 0.0;
  for (int dy = -kRadius; dy <= kRadius; ++dy) {
    const std::uint8_t* row = gray.ptr<std::uint8_t>(cy + dy);
    for (int dx = -kRadius; dx <= kRadius; ++dx) {
      if (dx * dx + dy * dy > kRadius * kRadius) continue;
      m10 += dx * row[cx + dx];
      m01 += dy * row[cx + dx];
    }
  }
  float angle = static_cast<float>(cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10)));
  return angle;
}

}  // namespace

GridOrbExtractor::GridOrbExtractor(const TrackerConfig& config)
    : orb_(cv::ORB::create(config.orb_features, static_cast<float>(config.orb_scale_factor),
                           config.orb_levels, 19, 0, 2, cv::ORB::HARRIS_SCORE, 31,
                           config.orb_fast_threshold)),
      search_orb_(cv::ORB::create(config.kf_reuse_orb_features,
                                  static_cast<float>(config.orb_scale_factor), config.orb_levels,
                                  19, 0, 2, cv::ORB::HARRIS_SCORE, 31,
                                  config.kf_reuse_orb_fast_threshold)),
      cell_px_(std::max(1, config.grid_cell_px)),
      fill_threshold_(config.orb_fast_threshold_min) {}

OrbFeatures GridOrbExtractor::extractAll(const cv::Mat& gray, const cv::Mat& allowed) const {
  OrbFeatures out;
  if (!gray.empty()) orb_->detectAndCompute(gray, allowed, out.keypoints, out.descriptors);
  return out;
}

OrbFeatures GridOrbExtractor::extractForSearch(const cv::Mat& gray, const cv::Mat& allowed) const {
  OrbFeatures out;
  if (!gray.empty()) search_orb_->detectAndCompute(gray, allowed, out.keypoints, out.descriptors);
  return out;
}

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
  for (std::size_t c = 0; c < best.size(); ++c) {
    if (best[c] < 0) continue;
    taken[c] = 1;
    out.keypoints.push_back(keypoints[static_cast<std::size_t>(best[c])]);
    out.descriptors.push_back(descriptors.row(best[c]));
  }
  fillEmptyCells(gray, allowed, cols, rows, taken, out);
  return out;
}

// Cells the pyramid ORB left empty get the strongest low-threshold FAST corner of level 0.
void GridOrbExtractor::fillEmptyCells(const cv::Mat& gray, const cv::Mat& allowed, int cols,
                                      int rows, const std::vector<char>& taken,
                                      OrbFeatures& out) const {
  if (fill_threshold_ <= 0) return;
  std::vector<cv::KeyPoint> corners;
  cv::FAST(gray, corners, fill_threshold_, true);
  constexpr float kBorder = 20.f;  // ORB's patch must fit around the corner
  std::vector<int> best(taken.size(), -1);
  for (int i = 0; i < static_cast<int>(corners.size()); ++i) {
    const cv::Point2f& p = corners[static_cast<std::size_t>(i)].pt;
    if (p.x < kBorder || p.y < kBorder || p.x >= static_cast<float>(gray.cols) - kBorder ||
        p.y >= static_cast<float>(gray.rows) - kBorder) {
      continue;
    }
    if (!allowed.empty() && !allowed.at<std::uint8_t>(cvRound(p.y), cvRound(p.x))) continue;
    const int cx = std::min(static_cast<int>(p.x) / cell_px_, cols - 1);
    const int cy = std::min(static_cast<int>(p.y) / cell_px_, rows - 1);
    const auto cell = static_cast<std::size_t>(cy * cols + cx);
    if (taken[cell]) continue;
    if (best[cell] < 0 || corners[static_cast<std::size_t>(i)].response >
                              corners[static_cast<std::size_t>(best[cell])].response) {
      best[cell] = i;
    }
  }
  std::vector<cv::KeyPoint> extra;
  for (int idx : best) {
    if (idx < 0) continue;
    cv::KeyPoint k = corners[static_cast<std::size_t>(idx)];
    k.size = 31.f;
    k.octave = 0;
    k.angle = intensityCentroidAngle(gray, k.pt);  // compute() keeps provided angles
    extra.push_back(k);
  }
  if (extra.empty()) return;
  cv::Mat extra_desc;
  orb_->compute(gray, extra, extra_desc);  // may drop keypoints it cannot describe
  if (extra.empty()) return;
  out.keypoints.insert(out.keypoints.end(), extra.begin(), extra.end());
  out.descriptors.push_back(extra_desc);
}

}  // namespace dynamap
