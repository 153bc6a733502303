#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace dynamap {

/// A 3D point in the world with the ORB descriptor of its first observation.
struct Landmark {
  Eigen::Vector3d p_W;
  cv::Mat descriptor;  ///< 1 x 32 CV_8U
  bool bad = false;    ///< seen on a moving object: never used again
  /// Keyframes that observed it: of this run and of the runs that saved the map it was loaded
  /// from.
  int keyframes = 0;
};

struct KeyframeObservation {
  std::uint64_t landmark_id = 0;
  Eigen::Vector2d px;
  double depth_m = 0.0;  ///< 0 = none
};

struct MapKeyframe {
  std::uint64_t id = 0;
  double timestamp_s = 0.0;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  std::vector<KeyframeObservation> observations;
  double masked_share = 0.0;  ///< share of its image under the motion mask when it was made
  /// Its view outside the motion mask on a coarse grid (view_coverage.hpp; not saved: empty,
  /// static everywhere, for a saved map's keyframes).
  cv::Mat static_cells;
  /// Culled (LocalMap::cull()): older keyframes already held its view. It follows the keyframe
  /// `parent` rigidly (T_W_C = parent's T_W_C * T_parent_C): its observations constrain the
  /// parent in bundle adjustment, its landmarks are searched as the parent's, and it is in no
  /// revisit, relocalization, keyframe list or saved map of its own.
  bool culled = false;
  std::uint64_t parent = 0;
  Eigen::Isometry3d T_parent_C = Eigen::Isometry3d::Identity();
  /// The keyframes culled into this one: their landmarks are searched as its own (revisits,
  /// the local search, relocalization), so culling takes no landmark out of reach.
  std::vector<std::uint64_t> culled_children;
  /// From a saved map (an earlier run): held fixed by bundle adjustment, and older than any
  /// keyframe of this run for revisits whatever its timestamp.
  bool loaded = false;
};

/// Everything the tracker's map holds, as plain data: what a saved map keeps and a later run
/// starts from. Ids are dense: landmarks[i] has id i, keyframes[k].id == k.
struct MapContents {
  std::vector<Landmark> landmarks;
  std::vector<MapKeyframe> keyframes;
};

}  // namespace dynamap
