#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/tracker_config.hpp"
#include "dynamap/core/tracking/feature_extractor.hpp"
#include "dynamap/core/tracking/local_map.hpp"
#include "dynamap/core/tracking/pose_optimizer.hpp"

namespace dynamap {

struct RelocalizationResult {
  bool ok = false;
  /// With !ok: the pose with most inliers found, too few to accept (0 inliers: none found).
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  int inliers = 0;
  std::vector<std::uint64_t> landmark_ids;  ///< inlier matches ...
  std::vector<cv::Point2f> px;              ///< ... and their pixels in the current frame
};

/// Of `points_W` in view at T_W_C with a measured depth at their pixel: the share the depth image
/// sees through (measured farther than the point by more than 10 % + 5 cm: free space where the
/// map has a surface). A wrong pose sees through most of the map; a right one through few
/// points (noise, objects moved since), movers in front hide points but see through none.
/// `checked`: how many points had a depth to compare.
double seenThroughShare(const std::vector<Eigen::Vector3d>& points_W, const Eigen::Isometry3d& T_W_C,
                        const cv::Mat& depth_m, const PinholeCamera& camera, double depth_min_m,
                        double depth_max_m, int* checked);

/// Recovers the pose of a frame from ORB descriptor matches (brute-force Hamming, ratio test)
/// against the landmarks of the newest keyframes and of those near the last pose, PnP-RANSAC without a prior, then refinement.
/// Matches are first searched near the landmarks' projections with the last known pose, then,
/// if that fails, among all candidates.
class Relocalizer {
 public:
  Relocalizer(const TrackerConfig& config, const PoseOptimizer& optimizer);
  /// `T_W_C_last`: the last tracked pose; near it, fewer inliers do
  /// (TrackerConfig::reloc_near_last_min_inliers).
  RelocalizationResult relocalize(const OrbFeatures& features, const cv::Mat& depth_m,
                                  const LocalMap& map, const PinholeCamera& camera,
                                  const Eigen::Isometry3d& T_W_C_last) const;
  /// The same against given candidates (e.g. the landmarks around the keyframes that place
  /// recognition found), `T_W_C_hint` guiding the first search; a pose is solved from
  /// `fewest_matches` matches on.
  RelocalizationResult relocalizeAgainst(const OrbFeatures& features, const cv::Mat& depth_m,
                                         const LandmarkCandidates& c, const PinholeCamera& camera,
                                         const Eigen::Isometry3d& T_W_C_hint,
                                         int fewest_matches) const;

 private:
  RelocalizationResult relocalizeNear(const OrbFeatures& features, const cv::Mat& depth_m,
                                      const LandmarkCandidates& c, const PinholeCamera& camera,
                                      const Eigen::Isometry3d& T_W_C_hint,
                                      const Eigen::Isometry3d* T_W_C_last,
                                      int fewest_matches) const;
  std::vector<std::uint64_t> candidateKeyframes(const LocalMap& map,
                                                const Eigen::Isometry3d& T_W_C_last) const;
  /// match[q] = candidate index of query q or -1.
  RelocalizationResult solve(const OrbFeatures& features, const cv::Mat& dist,
                             const cv::Mat& depth_m, const std::vector<std::uint64_t>& ids,
                             const std::vector<Eigen::Vector3d>& points,
                             const std::vector<int>& match,
                             const Eigen::Isometry3d* T_W_C_last, int fewest_matches) const;
  /// Enough inliers for `T_W_C`: reloc_min_inliers, or fewer near `T_W_C_last`.
  bool enoughInliers(int inliers, const Eigen::Isometry3d& T_W_C,
                     const Eigen::Isometry3d* T_W_C_last) const;

  TrackerConfig config_;
  const PoseOptimizer& optimizer_;
};

}  // namespace dynamap
