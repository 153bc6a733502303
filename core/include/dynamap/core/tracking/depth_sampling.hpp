#pragma once

#include <algorithm>
#include <cmath>

#include <opencv2/core.hpp>

#include "dynamap/core/rounding.hpp"

namespace dynamap {

/// Depth (metres) at the nearest pixel of (u, v), or 0 when missing, outside [min_m, max_m] or
/// on a depth discontinuity (the 3x3 neighbourhood spans more than 4 % of the depth + 1 cm).
inline double sampleDepth(const cv::Mat& depth_m, float u, float v, double min_m, double max_m) {
  if (depth_m.empty() || depth_m.type() != CV_32FC1) return 0.0;
  const int x = static_cast<int>(roundHalfAway(u));
  const int y = static_cast<int>(roundHalfAway(v));
  if (x < 1 || y < 1 || x >= depth_m.cols - 1 || y >= depth_m.rows - 1) return 0.0;
  const float z = depth_m.at<float>(y, x);
  if (!(z >= min_m && z <= max_m)) return 0.0;
  float lo = z, hi = z;
  for (int dy = -1; dy <= 1; ++dy) {
    const float* row = depth_m.ptr<float>(y + dy);
    for (int dx = -1; dx <= 1; ++dx) {
      const float d = row[x + dx];
      if (!(d > 0.f)) return 0.0;
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  }
  if (hi - lo > 0.04f * z + 0.01f) return 0.0;
  return z;
}

}  // namespace dynamap
