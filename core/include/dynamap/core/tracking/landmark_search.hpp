#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/tracking/feature_extractor.hpp"

namespace dynamap {

/// Landmarks that may be seen again: ids, stacked descriptors (one row each) and positions.
struct LandmarkCandidates {
  std::vector<std::uint64_t> ids;
  cv::Mat descriptors;
  std::vector<Eigen::Vector3d> points;
};

/// The landmarks of `all` whose id `keep` accepts, in their order.
LandmarkCandidates landmarksWhere(const LandmarkCandidates& all,
                                  const std::function<bool(std::uint64_t)>& keep);

/// `all` without the landmarks in `ids`.
LandmarkCandidates withoutLandmarks(const LandmarkCandidates& all,
                                    const std::vector<std::uint64_t>& ids);

struct LandmarkSearchParams {
  double radius_px = 10.0;        ///< keypoint within this distance of the projection
  int max_hamming = 50;           ///< descriptor distance gate
  float ratio = 0.8f;             ///< best / second-best descriptor distance (Lowe)
  double depth_tolerance = 0.05;  ///< |measured - projected depth| <= tolerance * measured
};

/// Search by projection (ORB-SLAM's "track local map", done at keyframes): each candidate is
/// projected with T_W_C and matched to the ORB keypoint near it with the closest descriptor.
/// A keypoint with measured depth (depth_m[i] > 0) must also agree with the landmark's depth.
/// Returns, per keypoint, the candidate index or -1; each candidate goes to one keypoint at most.
std::vector<int> searchByProjection(const OrbFeatures& features, const std::vector<double>& depth_m,
                                    const LandmarkCandidates& candidates,
                                    const Eigen::Isometry3d& T_W_C, const PinholeCamera& camera,
                                    const LandmarkSearchParams& params);

}  // namespace dynamap
