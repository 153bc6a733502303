#pragma once

#include <cmath>

#include <Eigen/Geometry>

#include "dynamap/core/tracker.hpp"
#include "synthetic_scene.hpp"

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

/// The map a tracker (default config, no motion filter) saves after frames [0, frames) of
/// `scene` along smoothPath(i, frames), 30 frames/s: poses in the frame of smoothPath(0).
inline MapContents savedMapAlongSmoothPath(const SyntheticScene& scene, int frames) {
  Tracker tracker(scene.camera(), TrackerConfig{}, nullptr);
  for (int i = 0; i < frames; ++i) {
    const RenderedFrame r = scene.render(smoothPath(i, frames), i / 30.0);
    RgbdFrame f;
    f.index = static_cast<std::size_t>(i);
    f.timestamp_s = i / 30.0;
    f.bgr = r.bgr;
    f.depth_m = r.depth_m;
    tracker.track(f);
  }
  tracker.finish();
  return tracker.mapContents();
}

}  // namespace dynamap::test
