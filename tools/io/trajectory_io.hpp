#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "tum_dataset.hpp"  // DatasetError

namespace dynamap {

struct TimedPose {
  double timestamp_s;
  Eigen::Isometry3d T_W_C;  ///< camera -> world
};

/// Reads a TUM trajectory ("timestamp tx ty tz qx qy qz qw"; '#' lines skipped; ',' and tabs
/// count as spaces). Like the benchmark scripts (a dict keyed by timestamp), a later line with
/// the same timestamp replaces an earlier one; the result is sorted by timestamp.
/// Quaternions are normalised; a quaternion of norm ~0 gives the identity rotation.
/// Throws DatasetError "file:line: ..." for a malformed line, "cannot open file" if missing.
std::vector<TimedPose> readTrajectory(const std::string& path);

/// Writes a TUM trajectory: timestamp with 6 decimals, then tx ty tz qx qy qz qw with 9
/// significant digits. Written to path + ".tmp" then renamed (atomic). Throws on I/O error.
void writeTrajectory(const std::string& path, const std::vector<TimedPose>& poses);

/// The TUM line format of one pose, without newline.
std::string formatTumPose(const TimedPose& pose);

}  // namespace dynamap
