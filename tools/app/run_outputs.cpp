#include "run_outputs.hpp"

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "html_report.hpp"
#include "image_io.hpp"
#include "json_io.hpp"
#include "map_report.hpp"
#include "output_files.hpp"
#include "trajectory_plot.hpp"

namespace dynamap {
namespace fs = std::filesystem;

namespace {

std::string outPath(const RunOptions& options, const std::string& name) {
  return (fs::path(options.out_dir) / name).string();
}

std::string framesTable(const RunResult& result) {
  std::ostringstream out;
  out << "# timestamp status\n";
  char line[96];
  for (std::size_t i = 0; i < result.trajectory.size(); ++i) {
    std::snprintf(line, sizeof(line), "%.6f %s\n", result.trajectory[i].timestamp_s,
                  i < result.frame_status.size() ? result.frame_status[i].c_str() : "unknown");
    out << line;
  }
  return out.str();
}

std::string timingsJson(const RunResult& result, const TimingRecorder& timings, double fps) {
  Json stages = Json::object();
  for (const auto& [name, s] : timings.allStats()) {
    stages[name] = {{"count", s.count},
                    {"median_ms", s.median_ms},
                    {"p95_ms", s.p95_ms},
                    {"mean_ms", s.mean_ms},
                    {"max_ms", s.max_ms}};
  }
  const StageStats tracking = timings.stats("tracking");
  // The frames alone (reading, tracking, mapping as they arrive), without finishing.
  const double loop_s = result.wall_time_s - result.finish_s;
  const double loop_fps =
      loop_s > 0 ? static_cast<double>(result.counts.frames_read) / loop_s : 0.0;
  const Json root = {{"mode", result.mode},
                     {"frames", result.counts.frames_read},
                     {"wall_time_s", result.wall_time_s},
                     {"frames_per_s", fps},
                     {"finish_s", result.finish_s},
                     {"frames_per_s_before_finish", loop_fps},
                     {"cpu_s", result.cpu_s},
                     {"cpu_ms_per_frame",
                      result.counts.frames_read > 0
                          ? 1000.0 * result.cpu_s / static_cast<double>(result.counts.frames_read)
                          : 0.0},
                     {"tracking_median_ms", tracking.median_ms},
                     {"tracking_p95_ms", tracking.p95_ms},
                     {"peak_memory_mib", peakMemoryMiB()},
                     {"stages", stages}};
  return dumpJson(root, 2) + "\n";
}

}  // namespace

void writeRunJson(const std::string& out_dir, const RunResult& result) {
  const RunCounts& c = result.counts;
  Json counts = {{"frames_read", c.frames_read},
                 {"tracked", c.tracked},
                 {"relocalized", c.relocalized},
                 {"posed_by_depth", c.posed_by_depth},
                 {"lost", c.lost},
                 {"bad_frames", c.bad_frames},
                 {"keyframes", c.keyframes},
                 {"culled_keyframes", c.culled_keyframes},
                 {"mapped_keyframes", c.mapped_keyframes},
                 {"skipped_realtime", c.skipped_realtime},
                 {"mapper_dropped", c.mapper_dropped}};
  if (c.loaded_keyframes > 0) {  // --load-map
    counts["loaded_keyframes"] = c.loaded_keyframes;
    counts["loaded_map_elements"] = c.loaded_map_elements;
  }
  Json root = {{"status", result.status},
               {"mode", result.mode},
               {"counts", counts},
               {"backend", result.backend}};
  if (!result.error.empty()) root["error"] = result.error;
  fs::create_directories(out_dir);
  writeTextFileAtomic((fs::path(out_dir) / "run.json").string(), dumpJson(root, 2) + "\n");
}

RunReport writeRunOutputs(const RunOptions& options, const TumSequence& sequence,
                          const RunResult& result, const TimingRecorder& timings) {
  RunReport report;
  writeTrajectory(outPath(options, "trajectory.txt"), result.trajectory);
  writeTrajectory(outPath(options, "keyframes.txt"), result.keyframes);
  writeTextFileAtomic(outPath(options, "frames.txt"), framesTable(result));
  report.frames_per_s = result.wall_time_s > 0
                            ? static_cast<double>(result.counts.frames_read) / result.wall_time_s
                            : 0.0;
  writeTextFileAtomic(outPath(options, "timings.json"),
                      timingsJson(result, timings, report.frames_per_s));

  Json metrics = Json::object();  // {"ate":…, "rpe":…, "map":…, "masks":…}
  std::optional<Alignment> alignment;
  if (const auto gt_path = sequence.groundTruthPath(); gt_path && result.trajectory.size() >= 2) {
    try {
      const auto gt = readTrajectory(*gt_path);
      report.evaluation = evaluateTrajectories(gt, result.trajectory, TrajectoryEvalOptions{});
      // Maps are compared after a whole-pose alignment: the ATE's position-only alignment
      // leaves the roll about a short, straight path free (alignPoses()).
      alignment = alignPoses(gt, result.trajectory, TrajectoryEvalOptions{}.max_time_diff_s);
      metrics.update(Json::parse(evaluationToJson(*report.evaluation)));
      // Jitter: the translation RPE over one frame (issue 48), beside the benchmark's 1 s RPE.
      TrajectoryEvalOptions one_frame;
      one_frame.rpe_delta = 1.0;
      one_frame.rpe_unit = RpeDeltaUnit::kFrames;
      metrics["rpe_one_frame"] =
          Json::parse(rpeToJson(computeRpe(gt, result.trajectory, one_frame)));
      TrajectoryPlotOptions plot;
      plot.title = "dynamap: " + fs::path(options.sequence_dir).filename().string();
      writeTrajectoryPlot(outPath(options, "trajectory.png"), gt, report.evaluation->ate, plot);
    } catch (const std::exception& e) {
      report.warnings += std::string("trajectory evaluation skipped: ") + e.what() + "\n";
    }
  }
  if (alignment && !result.map_dir.empty()) {
    try {
      report.map_metrics_json = mapMetricsJson(sequence.directory(), result.map_dir, *alignment);
      if (!report.map_metrics_json.empty()) metrics["map"] = Json::parse(report.map_metrics_json);
    } catch (const std::exception& e) {
      report.warnings += std::string("map metrics skipped: ") + e.what() + "\n";
    }
  }
  if (result.mask_scores.frames() > 0) {
    metrics["masks"] = Json::parse(result.mask_scores.toJson());
    metrics["tracker_masks"] = Json::parse(result.tracker_mask_scores.toJson());
  }
  if (!metrics.empty()) {
    writeTextFileAtomic(outPath(options, "metrics.json"), dumpJson(metrics) + "\n");
  }
  writeRunJson(options.out_dir, result);
  try {
    report.warnings +=
        writeHtmlReport(options.out_dir, fs::path(options.sequence_dir).filename().string(),
                        sequence.groundTruthPath().value_or(""));
  } catch (const std::exception& e) {
    report.warnings += std::string("report skipped: ") + e.what() + "\n";
  }
  return report;
}

void printRunSummary(std::ostream& out, const RunOptions& options, const RunResult& result,
                     const RunReport& report) {
  const RunCounts& c = result.counts;
  out << "run " << result.status << ": " << c.frames_read << " frames read, " << c.tracked
      << " tracked, " << c.posed_by_depth << " posed by depth, " << c.relocalized
      << " relocalized, " << c.lost << " lost, " << c.bad_frames << " bad; " << c.keyframes
      << " keyframes (" << c.culled_keyframes << " more culled); " << report.frames_per_s
      << " frames/s (" << result.finish_s << " s of it finishing)\n";
  if (!result.error.empty()) out << "error: " << result.error << "\n";
  if (report.evaluation) out << evaluationToTable(*report.evaluation);
  if (!report.map_metrics_json.empty()) out << "map: " << report.map_metrics_json << "\n";
  if (result.mask_scores.frames() > 0) {
    out << "keyframe masks vs ground truth: " << result.mask_scores.toJson() << "\n";
    out << "  (the tracker's own: " << result.tracker_mask_scores.toJson() << ")\n";
  }
  out << report.warnings;
  out << "outputs in " << options.out_dir << " (map: " << result.map_dir
      << "); report: " << (fs::path(options.out_dir) / "report.html").string() << "\n";
}

}  // namespace dynamap
