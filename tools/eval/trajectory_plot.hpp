#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "trajectory_eval.hpp"
#include "trajectory_io.hpp"

namespace dynamap {

struct TrajectoryPlotOptions {
  int width = 1000;
  int height = 800;
  std::string title;  ///< shown before "ATE RMSE ..." (e.g. the sequence name); may be empty
};

/// Top view of the ground truth (full, grey) and the aligned estimate coloured by its ATE
/// error (colour bar in cm), on the two axes with the largest ground-truth variance, with
/// metric ticks, legend and the ATE RMSE in the title. Returns a CV_8UC3 image.
cv::Mat renderTrajectoryPlot(const std::vector<TimedPose>& gt, const AteResult& ate,
                             const TrajectoryPlotOptions& options = {});

/// renderTrajectoryPlot written atomically (tmp + rename) to `png_path`. Throws on I/O error.
void writeTrajectoryPlot(const std::string& png_path, const std::vector<TimedPose>& gt,
                         const AteResult& ate, const TrajectoryPlotOptions& options = {});

}  // namespace dynamap
