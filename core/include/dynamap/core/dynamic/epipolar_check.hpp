#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace dynamap {

struct EpipolarOptions {
  double threshold_px = 1.0;
  int min_matches = 30;
  double min_parallax_px = 0.3;
  double confidence = 0.999;
  double homography_inlier_ratio = 0.95;
};

enum class EpipolarModel : std::uint8_t {
  kNone,         ///< degenerate (few matches / no motion): nothing flagged
  kFundamental,  ///< symmetric epipolar distance to a refitted F
  kHomography,   ///< low parallax: homography transfer error (F ill-conditioned)
};

struct EpipolarResult {
  EpipolarModel model = EpipolarModel::kNone;
  std::vector<float> residual_px;        ///< per match (0 when kNone)
  std::vector<std::uint8_t> is_dynamic;  ///< per match: residual > threshold
  cv::Mat F;                             ///< 3x3 CV_64F when model == kFundamental
};

/// Symmetric epipolar distance of p1 <-> p2 to F (x2^T F x1 = 0): the mean of the distances of
/// p2 to F x1 and of p1 to F^T x2, in pixels.
double symmetricEpipolarDistance(const cv::Matx33d& F, const cv::Point2f& p1,
                                 const cv::Point2f& p2);

/// Geometric motion check on frame-to-frame matches: RANSAC (USAC) fundamental matrix,
/// least-squares 8-point refit on the inliers, symmetric epipolar distance per match.
/// Degenerate inputs flag nothing.
EpipolarResult checkEpipolar(const std::vector<cv::Point2f>& prev_px,
                             const std::vector<cv::Point2f>& cur_px,
                             const EpipolarOptions& options);

}  // namespace dynamap
