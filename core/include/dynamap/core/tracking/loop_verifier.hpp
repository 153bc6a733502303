#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/tracker_config.hpp"
#include "dynamap/core/tracking/pose_optimizer.hpp"

namespace dynamap {

/// A keyframe as the loop closer keeps it: its STATIC features only (see LoopCloser), each
/// with the depth measured at it, and its pose estimate.
struct LoopKeyframe {
  std::uint64_t id = 0;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;                      ///< one 32-byte ORB row per keypoint
  std::vector<double> depth_m;              ///< per keypoint, 0 = none
  std::vector<std::uint64_t> landmark_ids;  ///< per keypoint, kNoLandmark = none (may be empty)
  static constexpr std::uint64_t kNoLandmark = ~std::uint64_t{0};
};

struct LoopVerifierParams {
  int max_hamming = 64;        ///< descriptor matching: distance gate ...
  float ratio = 0.8f;          ///< ... and Lowe ratio
  int ransac_iterations = 500;
  int min_inliers = 40;        ///< after the RGB-D refinement
  /// Convex hull of the inliers in the query image, as a share of the image: one poster
  /// seen twice (repeated texture) covers a small part of the view, a true revisit most of it.
  double min_hull_share = 0.2;
  /// Each neighbour of the candidate (its temporal neighbours) is checked at the pose the loop
  /// predicts through the odometry: inliers of its own matches there.
  int neighbour_min_inliers = 20;
  int min_consistent_neighbours = 1;  ///< neighbours that must agree (0 = no check)
};

/// A verified loop: the query keyframe seen from the matched one.
struct LoopConstraint {
  std::uint64_t query_id = 0;
  std::uint64_t match_id = 0;
  Eigen::Isometry3d T_Cmatch_Cquery = Eigen::Isometry3d::Identity();
  int inliers = 0;
  double hull_share = 0.0;
  int consistent_neighbours = 0;
};

/// Geometric verification of a place-recognition candidate: descriptor matches of the query's
/// keypoints against the candidate's keypoints with depth (3-D points in the candidate's
/// camera), PnP-RANSAC without a prior (AP3P), then the RGB-D refinement of PoseOptimizer
/// (reprojection + the query's measured depth). Accepted with enough inliers spread over the
/// image and agreement of the candidate's neighbours. Evidence comes only from the keyframes'
/// features, which the caller restricted to static ones. Thread-safe (no mutable state).
class LoopVerifier {
 public:
  LoopVerifier(const PinholeCamera& camera, const TrackerConfig& config,
               const LoopVerifierParams& params);

  /// `neighbours`: keyframes next to `candidate` (their poses consistent with its pose).
  std::optional<LoopConstraint> verify(const LoopKeyframe& query, const LoopKeyframe& candidate,
                                       const std::vector<const LoopKeyframe*>& neighbours) const;

 private:
  /// Correspondences query px <-> reference 3-D point (reference camera frame).
  std::vector<PoseCorrespondence> correspondences(const LoopKeyframe& query,
                                                  const LoopKeyframe& reference) const;
  int inliersAt(const std::vector<PoseCorrespondence>& corr,
                const Eigen::Isometry3d& T_Cref_Cquery) const;
  double hullShare(const std::vector<PoseCorrespondence>& corr,
                   const std::vector<std::uint8_t>& inlier) const;

  PinholeCamera camera_;
  TrackerConfig config_;
  LoopVerifierParams params_;
  PoseOptimizer optimizer_;
};

}  // namespace dynamap
