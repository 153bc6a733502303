#include "dynamap/core/camera.hpp"

#include <stdexcept>

namespace dynamap {

bool PinholeCamera::hasDistortion() const {
  for (double d : distortion) {
    if (d != 0.0) return true;
  }
  return false;
}

std::vector<std::string> cameraPresetNames() { return {"freiburg1", "freiburg2", "freiburg3"}; }

PinholeCamera cameraPreset(const std::string& name) {
  // Values published with the TUM RGB-D benchmark ("File Formats" -> intrinsic parameters).
  PinholeCamera cam;
  if (name == "freiburg1") {
    cam.fx = 517.3, cam.fy = 516.5, cam.cx = 318.6, cam.cy = 255.3;
    cam.distortion = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
  } else if (name == "freiburg2") {
    cam.fx = 520.9, cam.fy = 521.0, cam.cx = 325.1, cam.cy = 249.7;
    cam.distortion = {0.2312, -0.7849, -0.0033, -0.0001, 0.9172};
  } else if (name == "freiburg3") {
    cam.fx = 535.4, cam.fy = 539.2, cam.cx = 320.1, cam.cy = 247.6;
  } else {
    throw std::invalid_argument("unknown camera preset '" + name +
                                "' (known: freiburg1, freiburg2, freiburg3, custom)");
  }
  return cam;
}

}  // namespace dynamap
