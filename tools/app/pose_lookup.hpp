#pragma once

#include <optional>
#include <vector>

#include "trajectory_io.hpp"

namespace dynamap {

/// Poses of a given trajectory (e.g. motion capture at 100 Hz) at arbitrary times: linear
/// interpolation of position and slerp of rotation between the two bracketing poses, when
/// both lie within `max_gap_s` of the query; nothing outside the trajectory's time span.
class PoseLookup {
 public:
  explicit PoseLookup(std::vector<TimedPose> poses, double max_gap_s = 0.05);
  std::optional<Eigen::Isometry3d> at(double timestamp_s) const;

 private:
  std::vector<TimedPose> poses_;  // sorted by time
  double max_gap_s_;
};

}  // namespace dynamap
