#pragma once

#include <string>

#include "trajectory_eval.hpp"

namespace dynamap {

/// Map metrics of a run (shared/data/dynamic/README.md, "Metrics") when `sequence_dir` holds
/// reference_static.ply: the exported map (map_dir/cloud.ply, else mesh.ply vertices) moved by
/// the ATE alignment into the ground-truth frame. Returns a JSON object, or "" when the
/// sequence has no reference clouds. Throws std::runtime_error naming an unreadable file.
std::string mapMetricsJson(const std::string& sequence_dir, const std::string& map_dir,
                           const Alignment& alignment);

}  // namespace dynamap
