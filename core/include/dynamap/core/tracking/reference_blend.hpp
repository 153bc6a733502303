#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

namespace dynamap {

/// A frame of the trajectory: its pose as tracked, and the correction the keyframes' final
/// poses give it (the final pose of its reference keyframe times the frame's pose relative to
/// that keyframe when it was tracked, times the tracked pose's inverse).
struct ReferencedFrame {
  double timestamp_s = 0.0;
  bool has_ref = false;  ///< false: no reference keyframe (before the map, lost): no correction
  std::uint64_t ref_kf = 0;
  Eigen::Isometry3d T_W_C_tracked = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();  ///< used when has_ref
};

/// Final poses of the frames, in order. Where the reference keyframe changes, the corrections
/// of the two keyframes differ (bundle adjustment moved them differently after the frames were
/// tracked), and each frame taken alone by its reference would jump there: the jump is spread
/// over the frames since the previous change, linearly in time (translation, and rotation by
/// slerp), so the trajectory is continuous and every switch frame keeps its own correction.
/// A frame without a reference keeps its tracked pose, and ends a span.
std::vector<Eigen::Isometry3d> blendReferenceSwitches(const std::vector<ReferencedFrame>& frames);

}  // namespace dynamap
