#pragma once

#include <string>

namespace dynamap {

/// Turns a finished run folder into a page a person can read at a glance. Reads whatever
/// exists in `out_dir` (run.json, metrics.json, timings.json, trajectory.txt, trajectory.png,
/// map/cloud.ply or map/mesh.ply) and writes, atomically:
///   out_dir/map_preview_{top,oblique_1,oblique_2}.png  (when a map exists)
///   out_dir/ate_over_time.png   (when `ground_truth_path` is given and evaluates)
///   out_dir/trajectory.png      (only when missing and the ground truth evaluates)
///   out_dir/report.html         (static, no JavaScript; images by relative path)
/// A missing or unreadable input leaves its section out and is noted on the page. Returns
/// those notes, one per line ("" when everything was found). Throws std::runtime_error only
/// when report.html cannot be written. Not thread-safe for the same folder.
std::string writeHtmlReport(const std::string& out_dir, const std::string& sequence_name,
                            const std::string& ground_truth_path = "");

}  // namespace dynamap
