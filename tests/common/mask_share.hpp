#pragma once

#include <opencv2/core.hpp>

namespace dynamap::test {

/// Share of the pixels of `r` that `mask` (CV_8UC1) covers.
inline double maskedShare(const cv::Mat& mask, const cv::Rect& r) {
  return cv::countNonZero(mask(r)) / static_cast<double>(r.area());
}

}  // namespace dynamap::test
