#include "dynamap/system/trajectory.hpp"

#include <cstdio>

#include "dynamap/system/atomic_file.hpp"

namespace dynamap {

std::string formatTumPose(const TimedPose& pose) {
  const Eigen::Vector3d t = pose.T_W_C.translation();
  const Eigen::Quaterniond q(pose.T_W_C.linear());
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer), "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g", pose.timestamp_s,
                t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
  return buffer;
}

void writeTrajectory(const std::string& path, const std::vector<TimedPose>& poses) {
  std::string text = "# timestamp tx ty tz qx qy qz qw (camera to world)\n";
  for (const TimedPose& pose : poses) {
    text += formatTumPose(pose);
    text += '\n';
  }
  writeTextFileAtomic(path, text);
}

}  // namespace dynamap
