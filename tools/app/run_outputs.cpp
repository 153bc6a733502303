#include "run_outputs.hpp"

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "html_report.hpp"
#include "image_io.hpp"
#include "json_writer.hpp"
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
  JsonObject stages;
  for (const auto& [name, s] : timings.allStats()) {
    JsonObject stage;
    stage.add("count", static_cast<std::uint64_t>(s.count))
        .add("median_ms", s.median_ms)
        .add("p95_ms", s.p95_ms)
        .add("mean_ms", s.mean_ms)
        .add("max_ms", s.max_ms);
    stages.add(name, stage);
  }
  const StageStats tracking = timings.stats("tracking");
  JsonObject root;
  root.add("mode", result.mode)
      .add("frames", static_cast<std::uint64_t>(result.counts.frames_read))
      .add("wall_time_s", result.wall_time_s)
      .add("frames_per_s", fps)
      .add("tracking_median_ms", tracking.median_ms)
      .add("tracking_p95_ms", tracking.p95_ms)
      .add("peak_memory_mib", peakMemoryMiB())
      .add("stages", stages);
  return root.str(2) + "\n";
}

/// {"a":1} + {"b":2} -> {"a":1, "b":2} (both must be non-empty JSON objects).
std::string mergeJsonObjects(const std::string& a, const std::string& b) {
  const auto a_end = a.find_last_of('}');
  const auto b_begin = b.find('{');
  return a.substr(0, a_end) + ", " + b.substr(b_begin + 1);
}

}  // namespace

void writeRunJson(const std::string& out_dir, const RunResult& result) {
  const RunCounts& c = result.counts;
  JsonObject counts;
  counts.add("frames_read", static_cast<std::uint64_t>(c.frames_read))
      .add("tracked", static_cast<std::uint64_t>(c.tracked))
      .add("relocalized", static_cast<std::uint64_t>(c.relocalized))
      .add("lost", static_cast<std::uint64_t>(c.lost))
      .add("bad_frames", static_cast<std::uint64_t>(c.bad_frames))
      .add("keyframes", static_cast<std::uint64_t>(c.keyframes))
      .add("mapped_keyframes", static_cast<std::uint64_t>(c.mapped_keyframes))
      .add("skipped_realtime", static_cast<std::uint64_t>(c.skipped_realtime))
      .add("mapper_dropped", static_cast<std::uint64_t>(c.mapper_dropped));
  JsonObject root;
  root.add("status", result.status)
      .add("mode", result.mode)
      .add("counts", counts)
      .add("backend", result.backend);
  if (!result.error.empty()) root.add("error", result.error);
  fs::create_directories(out_dir);
  writeTextFileAtomic((fs::path(out_dir) / "run.json").string(), root.str(2) + "\n");
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

  std::string metrics_json;  // {"ate":…, "rpe":…, "map":…}
  std::optional<Alignment> alignment;
  if (const auto gt_path = sequence.groundTruthPath(); gt_path && result.trajectory.size() >= 2) {
    try {
      const auto gt = readTrajectory(*gt_path);
      report.evaluation = evaluateTrajectories(gt, result.trajectory, TrajectoryEvalOptions{});
      // Maps are compared after a whole-pose alignment: the ATE's position-only alignment
      // leaves the roll about a short, straight path free (alignPoses()).
      alignment = alignPoses(gt, result.trajectory, TrajectoryEvalOptions{}.max_time_diff_s);
      metrics_json = evaluationToJson(*report.evaluation);
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
      if (!report.map_metrics_json.empty()) {
        metrics_json = mergeJsonObjects(metrics_json, "{\"map\": " + report.map_metrics_json + "}");
      }
    } catch (const std::exception& e) {
      report.warnings += std::string("map metrics skipped: ") + e.what() + "\n";
    }
  }
  if (result.mask_scores.frames() > 0) {
    const std::string masks = "{\"masks\": " + result.mask_scores.toJson() + "}";
    metrics_json = metrics_json.empty() ? masks : mergeJsonObjects(metrics_json, masks);
  }
  if (!metrics_json.empty()) {
    writeTextFileAtomic(outPath(options, "metrics.json"), metrics_json + "\n");
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
      << " tracked, " << c.relocalized << " relocalized, " << c.lost << " lost, " << c.bad_frames
      << " bad; " << c.keyframes << " keyframes; " << report.frames_per_s << " frames/s\n";
  if (!result.error.empty()) out << "error: " << result.error << "\n";
  if (report.evaluation) out << evaluationToTable(*report.evaluation);
  if (!report.map_metrics_json.empty()) out << "map: " << report.map_metrics_json << "\n";
  if (result.mask_scores.frames() > 0) {
    out << "keyframe masks vs ground truth: " << result.mask_scores.toJson() << "\n";
  }
  out << report.warnings;
  out << "outputs in " << options.out_dir << " (map: " << result.map_dir
      << "); report: " << (fs::path(options.out_dir) / "report.html").string() << "\n";
}

}  // namespace dynamap
