#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "trajectory_eval.hpp"

namespace dynamap {

struct AteOverTimePlotOptions {
  int width = 1000;
  int height = 360;
  std::string title;  ///< shown before "ATE over time"; may be empty
};

/// ATE error (cm) of each associated pose against time since the first pair (s), with metric
/// ticks, axis labels, the RMSE as a dashed line and RMSE / max in the title. CV_8UC3 image.
/// An AteResult without pairs gives a plot with empty axes.
cv::Mat renderAteOverTimePlot(const AteResult& ate, const AteOverTimePlotOptions& options = {});

/// renderAteOverTimePlot written atomically to `png_path`. Throws on I/O error.
void writeAteOverTimePlot(const std::string& png_path, const AteResult& ate,
                          const AteOverTimePlotOptions& options = {});

}  // namespace dynamap
