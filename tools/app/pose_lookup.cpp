#include "pose_lookup.hpp"

#include <algorithm>

namespace dynamap {

PoseLookup::PoseLookup(std::vector<TimedPose> poses, double max_gap_s)
    : poses_(std::move(poses)), max_gap_s_(max_gap_s) {
  std::sort(poses_.begin(), poses_.end(),
            [](const TimedPose& a, const TimedPose& b) { return a.timestamp_s < b.timestamp_s; });
}

std::optional<Eigen::Isometry3d> PoseLookup::at(double t) const {
  if (poses_.empty()) return std::nullopt;
  auto hi = std::lower_bound(poses_.begin(), poses_.end(), t,
                             [](const TimedPose& p, double v) { return p.timestamp_s < v; });
  if (hi != poses_.end() && hi->timestamp_s == t) return hi->T_W_C;
  if (hi == poses_.begin() || hi == poses_.end()) return std::nullopt;
  const auto lo = hi - 1;
  if (t - lo->timestamp_s > max_gap_s_ || hi->timestamp_s - t > max_gap_s_) return std::nullopt;
  const double a = (t - lo->timestamp_s) / (hi->timestamp_s - lo->timestamp_s);
  const Eigen::Quaterniond q0(lo->T_W_C.linear());
  const Eigen::Quaterniond q1(hi->T_W_C.linear());
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q0.slerp(a, q1).normalized().toRotationMatrix();
  T.translation() = (1.0 - a) * lo->T_W_C.translation() + a * hi->T_W_C.translation();
  return T;
}

}  // namespace dynamap
