#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "dynamap/system/trajectory.hpp"  // TimedPose, writeTrajectory, formatTumPose
#include "tum_dataset.hpp"                // DatasetError

namespace dynamap {

/// Reads a TUM trajectory ("timestamp tx ty tz qx qy qz qw"; '#' lines skipped; ',' and tabs
/// count as spaces). Like the benchmark scripts (a dict keyed by timestamp), a later line with
/// the same timestamp replaces an earlier one; the result is sorted by timestamp.
/// Quaternions are normalised; a quaternion of norm ~0 gives the identity rotation.
/// Throws DatasetError "file:line: ..." for a malformed line, "cannot open file" if missing.
std::vector<TimedPose> readTrajectory(const std::string& path);

}  // namespace dynamap
