#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace dynamap {

struct TimedPose {
  double timestamp_s;
  Eigen::Isometry3d T_W_C;  ///< camera -> world
};

/// Writes a TUM trajectory: timestamp with 6 decimals, then tx ty tz qx qy qz qw with 9
/// significant digits. Written to path + ".tmp" then renamed (atomic). Throws on I/O error.
void writeTrajectory(const std::string& path, const std::vector<TimedPose>& poses);

/// The TUM line format of one pose, without newline.
std::string formatTumPose(const TimedPose& pose);

}  // namespace dynamap
