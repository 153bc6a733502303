#pragma once

#include <opencv2/core.hpp>

namespace dynamap {

/// Colour image with the dynamic mask (255 = moving) tinted red.
cv::Mat maskOverlay(const cv::Mat& bgr, const cv::Mat& dynamic_mask);

/// Peak resident memory of this process (VmHWM) in MiB, 0 when unknown.
double peakMemoryMiB();

}  // namespace dynamap
