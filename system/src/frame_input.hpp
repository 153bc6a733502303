#pragma once

#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/frame.hpp"

namespace dynamap {

/// Turns caller images into the tracker's RgbdFrame: checks types and sizes, copies, converts
/// depth to metres and undistorts (maps computed once) when the camera has distortion.
class FrameInput {
 public:
  FrameInput() = default;
  FrameInput(const PinholeCamera& camera, double depth_scale);

  /// Throws std::invalid_argument naming the problem (type, channels, size).
  RgbdFrame prepare(const cv::Mat& bgr, const cv::Mat& depth, double timestamp_s) const;

 private:
  double depth_scale_ = 5000.0;
  cv::Mat map_x_;  // empty when the camera has no distortion
  cv::Mat map_y_;
};

}  // namespace dynamap
