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
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  int inliers = 0;
  std::vector<std::uint64_t> landmark_ids;  ///< inlier matches ...
  std::vector<cv::Point2f> px;              ///< ... and their pixels in the current frame
};

/// Recovers the pose of a frame from ORB descriptor matches (brute-force Hamming, ratio test)
/// against the landmarks of the newest keyframes, PnP-RANSAC without a prior, then refinement.
class Relocalizer {
 public:
  Relocalizer(const TrackerConfig& config, const PoseOptimizer& optimizer);
  RelocalizationResult relocalize(const OrbFeatures& features, const cv::Mat& depth_m,
                                  const LocalMap& map) const;

 private:
  TrackerConfig config_;
  const PoseOptimizer& optimizer_;
};

}  // namespace dynamap
