#pragma once

#include <string>

#include "dynamap/core/motion_filter.hpp"

namespace dynamap {

/// Path of the mask for a colour frame: DIR/<stem of the colour file>.png, or
/// DIR/<timestamp with 6 decimals>.png.
std::string maskPathFor(const std::string& masks_dir, const std::string& rgb_path,
                        double timestamp_s);

/// Reads a per-frame mask (pixels equal to 255 are dynamic, every other value static).
/// Returns an empty Mat when the file is absent; throws std::runtime_error when it exists but
/// cannot be decoded or has the wrong size.
cv::Mat readDynamicMask(const std::string& path, int width, int height);

/// A MotionFilter that uses masks given on disk (`--masks DIR`) instead of computing them.
class GivenMaskFilter : public MotionFilter {
 public:
  explicit GivenMaskFilter(std::string masks_dir) : masks_dir_(std::move(masks_dir)) {}
  /// The colour path of the next frame (set by the pipeline before track()).
  void setNextRgbPath(const std::string& rgb_path) { next_rgb_path_ = rgb_path; }
  void beginFrame(const RgbdFrame& frame) override;
  MotionFilterOutput filter(const MotionFilterInput& input) override;
  /// The mask read by the last beginFrame() (empty when the file is absent).
  const cv::Mat& currentMask() const { return mask_; }

 private:
  std::string masks_dir_;
  std::string next_rgb_path_;
  cv::Mat mask_;
};

}  // namespace dynamap
