#include "trajectory_io.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <map>

namespace dynamap {
namespace {

/// Rotation of quaternion (x, y, z, w) as the benchmark's transform44 builds it: normalised;
/// identity when the squared norm is below 4 * machine epsilon.
Eigen::Matrix3d rotationFromQuaternion(double qx, double qy, double qz, double qw) {
  const double squared_norm = qx * qx + qy * qy + qz * qz + qw * qw;
  if (squared_norm < 4.0 * std::numeric_limits<double>::epsilon()) {
    return Eigen::Matrix3d::Identity();
  }
  return Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
}

}  // namespace

std::vector<TimedPose> readTrajectory(const std::string& path) {
  std::map<double, Eigen::Isometry3d> by_time;
  for (const ListLine& line : readListFile(path)) {
    if (line.fields.size() != 8) {
      throw DatasetError(path + ":" + std::to_string(line.line_number) +
                         ": expected 8 fields 'timestamp tx ty tz qx qy qz qw', found " +
                         std::to_string(line.fields.size()));
    }
    static const std::array<const char*, 8> kNames = {"timestamp", "tx", "ty", "tz",
                                                      "qx",        "qy", "qz", "qw"};
    std::array<double, 8> v{};
    for (std::size_t k = 0; k < 8; ++k) {
      v[k] = parseNumberField(line.fields[k], path, line.line_number, kNames[k]);
    }
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = rotationFromQuaternion(v[4], v[5], v[6], v[7]);
    T.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    by_time[v[0]] = T;
  }
  std::vector<TimedPose> poses;
  poses.reserve(by_time.size());
  for (const auto& [t, T] : by_time) poses.push_back({t, T});
  return poses;
}

}  // namespace dynamap
