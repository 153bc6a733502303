#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/timing.hpp"
#include "dynamap/core/tracker_config.hpp"

namespace dynamap {

/// One 2D (and optionally depth) observation of a known world point.
struct PoseCorrespondence {
  Eigen::Vector3d p_W;
  Eigen::Vector2d px;
  double depth_m = 0.0;      ///< measured depth at px, 0 = none
  double sigma_scale = 1.0;  ///< pixel std-dev multiplier (ORB octave scale)
};

struct PoseEstimate {
  bool ok = false;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  std::vector<std::uint8_t> inlier;  ///< one flag per correspondence
  int inliers = 0;
};

/// PnP + RANSAC (seeded with a predicted pose), then motion-only Ceres refinement of
/// reprojection + depth residuals with a Huber loss and two rounds of outlier rejection.
/// Thread-safe (no mutable state).
class PoseOptimizer {
 public:
  PoseOptimizer(const PinholeCamera& camera, const TrackerConfig& config);

  /// `timings` may be null; records "pnp" and "pose_refine".
  PoseEstimate estimate(const std::vector<PoseCorrespondence>& corr,
                        const Eigen::Isometry3d& T_W_C_guess, TimingRecorder* timings) const;

  /// RANSAC only; fills inlier flags. Returns false when RANSAC found no model. With
  /// `use_guess`, T_W_C seeds iterative PnP samples; otherwise minimal AP3P samples.
  bool ransac(const std::vector<PoseCorrespondence>& corr, Eigen::Isometry3d& T_W_C,
              std::vector<std::uint8_t>& inlier, bool use_guess = true,
              int iterations = 0) const;  ///< iterations 0 = config's

  /// Motion-only refinement over the flagged correspondences; re-classifies inliers with a
  /// chi-square test. Returns the inlier count.
  /// `predicted` (may be null): the constant-velocity prediction; with
  /// motion_prior_sigma_m > 0 the pose is held near it with that standard deviation of the
  /// camera centre (and motion_prior_sigma_deg of the rotation), which only matters when few
  /// matches constrain the pose (a hand-held camera does not jump while walkers hide the scene).
  int refine(const std::vector<PoseCorrespondence>& corr, Eigen::Isometry3d& T_W_C,
             std::vector<std::uint8_t>& inlier, const Eigen::Isometry3d* predicted = nullptr) const;

 private:
  PinholeCamera camera_;
  TrackerConfig config_;
};

}  // namespace dynamap
