#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace dynamap {

/// Pinhole intrinsics of the colour camera (depth is registered to it).
/// `distortion` is OpenCV's (k1, k2, p1, p2, k3); all zero means already undistorted.
struct PinholeCamera {
  double fx = 535.4;
  double fy = 539.2;
  double cx = 320.1;
  double cy = 247.6;
  int width = 640;
  int height = 480;
  std::array<double, 5> distortion{0.0, 0.0, 0.0, 0.0, 0.0};

  bool hasDistortion() const;
  /// Pixel (u, v) with depth z (metres) -> point in the camera frame.
  Eigen::Vector3d backProject(double u, double v, double z_m) const {
    return {(u - cx) * z_m / fx, (v - cy) * z_m / fy, z_m};
  }
  /// Point in the camera frame -> pixel. Caller checks z > 0.
  Eigen::Vector2d project(const Eigen::Vector3d& p_C) const {
    return {fx * p_C.x() / p_C.z() + cx, fy * p_C.y() / p_C.z() + cy};
  }
};

/// TUM RGB-D presets: "freiburg1", "freiburg2" (published distortion), "freiburg3" (undistorted).
/// Throws std::invalid_argument naming the known presets for an unknown name.
PinholeCamera cameraPreset(const std::string& name);
std::vector<std::string> cameraPresetNames();

}  // namespace dynamap
