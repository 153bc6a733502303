#pragma once

#include <cmath>

#include <Eigen/Geometry>

namespace dynamap::test {

/// Smooth 6-DoF camera path: ~2 cm and ~0.7 deg per frame for n = 60.
inline Eigen::Isometry3d smoothPath(int i, int n) {
  const double s = static_cast<double>(i) / n;
  const double two_pi = 2.0 * M_PI;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() =
      Eigen::Vector3d(0.25 * std::sin(two_pi * s), 0.10 * std::sin(2 * two_pi * s), 0.40 * s);
  const double deg = M_PI / 180.0;
  T.linear() = (Eigen::AngleAxisd(6 * deg * std::sin(two_pi * s), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(4 * deg * std::sin(two_pi * s + 1.0), Eigen::Vector3d::UnitX()) *
                Eigen::AngleAxisd(3 * deg * std::sin(two_pi * s + 2.0), Eigen::Vector3d::UnitZ()))
                   .toRotationMatrix();
  return T;
}

}  // namespace dynamap::test
