#pragma once

#include <string>

namespace dynamap {

/// Motion-area removal parameters, bound to YAML keys "dynamic.<name>"
/// (tools/io/config_bind_dynamic.cpp).
struct DynamicConfig {
  std::string mode = "both";           ///< off | geometry | detector | both
  double epipolar_threshold_px = 1.0;  ///< matches farther from their epipolar line are dynamic
};

}  // namespace dynamap
