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
  double homography_inlier_ratio = 0.85;
  double reprojection_threshold_px = 4.0;    ///< rigid check (with depth): reprojection error
  double rigid_epipolar_threshold_px = 2.5;  ///< rigid check, matches without depth
  int ransac_iterations = 200;               ///< rigid check: minimal-sample iterations
  int bucket_px = 40;                        ///< model fit uses at most 2 matches per cell
};

enum class EpipolarModel : std::uint8_t {
  kNone,         ///< degenerate (few matches / no motion): nothing flagged
  kFundamental,  ///< symmetric epipolar distance to a refitted F
  kHomography,   ///< low parallax: homography transfer error (F ill-conditioned)
  kRigid,        ///< depth available: PnP pose, reprojection error (+ epipolar w/o depth)
};

struct EpipolarResult {
  EpipolarModel model = EpipolarModel::kNone;
  std::vector<float> residual_px;        ///< per match (0 when kNone)
  std::vector<std::uint8_t> is_dynamic;  ///< per match: residual > threshold
  cv::Mat F;                             ///< 3x3 CV_64F when model == kFundamental
  cv::Mat H;                             ///< 3x3 CV_64F when model == kHomography
  bool from_prior = false;  ///< kRigid: the given prior motion was taken (not RANSAC's)
};

/// Symmetric epipolar distance of p1 <-> p2 to F (x2^T F x1 = 0): the mean of the distances of
/// p2 to F x1 and of p1 to F^T x2, in pixels.
double symmetricEpipolarDistance(const cv::Matx33d& F, const cv::Point2f& p1,
                                 const cv::Point2f& p2);

/// Geometric motion check on frame-to-frame matches: RANSAC (USAC) fundamental matrix,
/// least-squares 8-point refit on the inliers, symmetric epipolar distance per match.
/// Degenerate inputs flag nothing. With `fit_subset` (one flag per match, 1 = may vote) the
/// models are fitted on the flagged matches only (too few: degenerate) and every match is
/// checked against them.
EpipolarResult checkEpipolar(const std::vector<cv::Point2f>& prev_px,
                             const std::vector<cv::Point2f>& cur_px, const EpipolarOptions& options,
                             const std::vector<std::uint8_t>& fit_subset = {});

/// Frame-to-frame camera motion as found by checkRigidMotion(): a current-frame point X maps
/// to the previous frame as R(rvec) X + tvec.
struct RigidMotion {
  cv::Vec3d rvec, tvec;
  bool valid = false;
};

/// The same check made well-conditioned with the current depth (RGB-D): the static camera
/// motion is a PnP-RANSAC pose from the current frame's 3-D points to the previous pixels,
/// fitted on a spatially bucketed subset of the matches (at most 2 per bucket_px cell) where
/// each inlier counts with its `fit_weight` (low on likely movers: detected people, last
/// frame's moving regions), so a large, richly textured mover cannot out-vote the background;
/// refined on its inliers.
/// A match with depth is dynamic if its reprojection error exceeds reprojection_threshold_px;
/// one without depth if its symmetric epipolar distance to the pose's F exceeds
/// rigid_epipolar_threshold_px.
/// Points beyond the depth range (no reading around them, away from the border) join the fit
/// as far points: they pin the rotation that a near, nearly planar static layer leaves
/// ambiguous with translation (which lets a large mover's motion fit the static layer to ~1 px).
/// Falls back to checkEpipolar() when too few matches have depth.
/// `K` = (fx, fy, cx, cy); `fit_weight` per match (empty = all 1); `estimated` (may be null)
/// gets the motion. `prior` (may be null): a motion known from elsewhere (the tracker's map);
/// used instead of RANSAC when at least a fifth of the fit matches agree with it.
EpipolarResult checkRigidMotion(const std::vector<cv::Point2f>& prev_px,
                                const std::vector<cv::Point2f>& cur_px, const cv::Mat& depth_m,
                                const cv::Vec4d& K, const std::vector<float>& fit_weight,
                                const EpipolarOptions& options, RigidMotion* estimated = nullptr,
                                const RigidMotion* prior = nullptr);

}  // namespace dynamap
