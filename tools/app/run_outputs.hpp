#pragma once

#include <optional>
#include <ostream>
#include <string>

#include "dynamap/core/timing.hpp"
#include "pipeline.hpp"
#include "run_options.hpp"
#include "trajectory_eval.hpp"
#include "tum_dataset.hpp"

namespace dynamap {

/// What writeRunOutputs computed (for the summary printed at the end).
struct RunReport {
  std::optional<TrajectoryEvaluation> evaluation;  ///< when the sequence has ground truth
  std::string map_metrics_json;                    ///< when reference clouds exist
  double frames_per_s = 0.0;
  std::string warnings;
};

/// Writes OUT/trajectory.txt, keyframes.txt, frames.txt (per-frame status), timings.json,
/// metrics.json + trajectory.png (with ground truth) and run.json. Each file is written
/// atomically; a failure to evaluate is reported in the summary, never loses the trajectory.
RunReport writeRunOutputs(const RunOptions& options, const TumSequence& sequence,
                          const RunResult& result, const TimingRecorder& timings);

/// OUT/run.json: status (complete | interrupted | failed), frame counts, error message.
void writeRunJson(const std::string& out_dir, const RunResult& result);

void printRunSummary(std::ostream& out, const RunOptions& options, const RunResult& result,
                     const RunReport& report);

}  // namespace dynamap
