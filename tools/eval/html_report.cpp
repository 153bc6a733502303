// report.html of a run folder: status, metrics, plots, map previews, timings (html_report.hpp).
#include "html_report.hpp"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <optional>
#include <sstream>
#include <vector>

#include "ate_over_time.hpp"
#include "html_report_style.hpp"
#include "image_io.hpp"
#include "json_io.hpp"
#include "map_preview.hpp"
#include "ply_colored.hpp"
#include "trajectory_eval.hpp"
#include "trajectory_plot.hpp"

namespace dynamap {
namespace {
namespace fs = std::filesystem;

constexpr std::size_t kMaxPreviewPoints = 2000000;  ///< big clouds: every k-th point

struct ReportInputs {
  std::string out_dir;
  std::string sequence_name;
  std::optional<Json> run, metrics, timings;
  bool trajectory_plot = false;
  bool ate_plot = false;
  std::string map_file;  ///< relative to out_dir, "" when no map
  std::size_t map_vertices = 0, map_triangles = 0;
  std::vector<std::string> previews;
  std::vector<std::string> notes;
};

std::string path(const ReportInputs& in, const std::string& name) {
  return (fs::path(in.out_dir) / name).string();
}

std::optional<Json> readOptionalJson(ReportInputs* in, const std::string& name) {
  const std::string file = path(*in, name);
  if (!fs::exists(file)) {
    in->notes.push_back(name + " not found");
    return std::nullopt;
  }
  try {
    return readJsonFile(file);
  } catch (const std::exception& e) {
    in->notes.push_back(e.what());
    return std::nullopt;
  }
}

/// ATE over time (and the trajectory plot when missing) from trajectory.txt + ground truth.
void writePlots(const std::string& gt_path, ReportInputs* in) {
  in->trajectory_plot = fs::exists(path(*in, "trajectory.png"));
  if (gt_path.empty()) return;
  try {
    const std::vector<TimedPose> gt = readTrajectory(gt_path);
    const std::vector<TimedPose> est = readTrajectory(path(*in, "trajectory.txt"));
    const TrajectoryEvaluation evaluation = evaluateTrajectories(gt, est, TrajectoryEvalOptions{});
    AteOverTimePlotOptions options;
    options.title = in->sequence_name;
    writeAteOverTimePlot(path(*in, "ate_over_time.png"), evaluation.ate, options);
    in->ate_plot = true;
    if (!in->trajectory_plot) {
      TrajectoryPlotOptions plot;
      plot.title = "dynamap: " + in->sequence_name;
      writeTrajectoryPlot(path(*in, "trajectory.png"), gt, evaluation.ate, plot);
      in->trajectory_plot = true;
    }
  } catch (const std::exception& e) {
    in->notes.push_back(std::string("trajectory evaluation: ") + e.what());
  }
}

void writePreviews(ReportInputs* in) {
  for (const char* name : {"map/cloud.ply", "map/mesh.ply"}) {
    if (fs::exists(path(*in, name))) {
      in->map_file = name;
      break;
    }
  }
  if (in->map_file.empty()) {
    in->notes.push_back("no map/cloud.ply or map/mesh.ply: no map previews");
    return;
  }
  try {
    const PlyData map =
        readPlyForPreview(path(*in, in->map_file), kMaxPreviewPoints, &in->map_vertices);
    in->map_triangles = map.triangles.size();
    std::vector<TimedPose> trajectory;
    if (fs::exists(path(*in, "trajectory.txt"))) {
      trajectory = readTrajectory(path(*in, "trajectory.txt"));
    }
    in->previews = writeMapPreviews(map, trajectory, in->out_dir);
    if (in->previews.empty()) in->notes.push_back(in->map_file + " has no vertices");
  } catch (const std::exception& e) {
    in->notes.push_back(std::string("map previews: ") + e.what());
  }
}

std::string escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// "rmse_m" -> "rmse", "frames_per_s" -> "frames/s", "trans_rmse_m" -> "trans rmse".
std::string label(std::string key) {
  for (const char* unit : {"_per_s", "_m", "_deg", "_ms", "_mib", "_s"}) {
    if (endsWith(key, unit)) {
      key = key.substr(0, key.size() - std::string(unit).size()) +
            (std::string(unit) == "_per_s" ? "/s" : "");
      break;
    }
  }
  for (char& c : key) c = c == '_' ? ' ' : c;
  return key;
}

std::string format(const std::string& key, const Json& v) {
  char text[64];
  if (v.is_null()) return "n/a";
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_string()) return escape(v.get<std::string>());
  if (!v.is_number()) return "&hellip;";
  const double x = v.get<double>();
  if (endsWith(key, "_per_s")) {
    std::snprintf(text, sizeof(text), "%.1f", x);
  } else if (endsWith(key, "_m")) {
    std::snprintf(text, sizeof(text), "%.2f cm", 100.0 * x);
  } else if (endsWith(key, "_deg")) {
    std::snprintf(text, sizeof(text), "%.3f&deg;", x);
  } else if (endsWith(key, "_ms")) {
    std::snprintf(text, sizeof(text), "%.1f ms", x);
  } else if (endsWith(key, "_mib")) {
    std::snprintf(text, sizeof(text), "%.0f MiB", x);
  } else if (endsWith(key, "_s")) {
    std::snprintf(text, sizeof(text), "%.2f s", x);
  } else if (std::abs(x) < 1e15 && x == std::floor(x)) {
    std::snprintf(text, sizeof(text), "%.0f", x);
  } else if (std::abs(x) < 0.01) {
    std::snprintf(text, sizeof(text), "%.3g", x);  // e.g. a ghost ratio of 1.4e-06
  } else {
    std::snprintf(text, sizeof(text), "%.3f", x);
  }
  return text;
}

/// Two-column table of the scalar members of `object`.
std::string keyValueTable(const std::string& caption, const Json& object) {
  std::ostringstream html;
  html << "<table class=\"kv\"><caption>" << escape(caption) << "</caption>\n";
  for (const auto& member : object.items()) {
    if (member.value().is_structured()) continue;
    html << "<tr><th>" << escape(label(member.key())) << "</th><td>"
         << format(member.key(), member.value()) << "</td></tr>\n";
  }
  html << "</table>\n";
  return html.str();
}

std::string image(const std::string& file, const std::string& alt, const std::string& cls) {
  return "<a href=\"" + escape(file) + "\"><img class=\"" + cls + "\" src=\"" + escape(file) +
         "\" alt=\"" + escape(alt) + "\"></a>\n";
}

std::string runSection(const ReportInputs& in) {
  std::ostringstream html;
  html << "<section id=\"run\"><h2>Run</h2>\n";
  if (!in.run) return html.str() + "<p>run.json not available.</p></section>\n";
  const std::string status = stringMember(*in.run, "status").value_or("unknown");
  html << "<p>Status: <span class=\"status " << escape(status) << "\">" << escape(status)
       << "</span>";
  if (auto backend = stringMember(*in.run, "backend"))
    html << " &middot; backend " << escape(*backend);
  html << "</p>\n";
  if (auto error = stringMember(*in.run, "error")) {
    html << "<p class=\"error\">Error: " << escape(*error) << "</p>\n";
  }
  if (const Json* counts = findMember(*in.run, "counts"); counts && counts->is_object()) {
    html << "<table class=\"counts\"><tr>";
    for (const auto& member : counts->items())
      html << "<th>" << escape(label(member.key())) << "</th>";
    html << "</tr><tr>";
    for (const auto& member : counts->items()) {
      html << "<td>" << format(member.key(), member.value()) << "</td>";
    }
    html << "</tr></table>\n";
  }
  return html.str() + "</section>\n";
}

std::string metricsSection(const ReportInputs& in) {
  std::ostringstream html;
  html << "<section id=\"metrics\"><h2>Metrics</h2>\n";
  if (!in.metrics)
    return html.str() + "<p>metrics.json not available (no ground truth?).</p></section>\n";
  html << "<div class=\"row\">\n";
  // Every object of metrics.json gets a table (ate, rpe, map and whatever is added later).
  if (!in.metrics->is_object()) return html.str() + "</div></section>\n";
  for (const auto& member : in.metrics->items()) {
    const std::string& key = member.key();
    const Json& part = member.value();
    if (!part.is_object()) continue;
    const std::string caption = key == "ate"   ? "ATE (absolute trajectory error)"
                                : key == "rpe" ? "RPE (relative pose error)"
                                : key == "map" ? "Map vs reference"
                                               : label(key);
    html << keyValueTable(caption, part);
  }
  return html.str() + "</div></section>\n";
}

std::string plotsSection(const ReportInputs& in) {
  std::ostringstream html;
  html << "<section id=\"trajectory\"><h2>Trajectory</h2>\n";
  if (in.trajectory_plot) html << image("trajectory.png", "trajectory plot", "plot");
  if (in.ate_plot) html << image("ate_over_time.png", "ATE over time", "wide");
  if (!in.trajectory_plot && !in.ate_plot) html << "<p>No ground truth: no trajectory plots.</p>\n";
  return html.str() + "</section>\n";
}

std::string mapSection(const ReportInputs& in) {
  std::ostringstream html;
  html << "<section id=\"map\"><h2>Map</h2>\n";
  if (in.map_file.empty()) return html.str() + "<p>No map was exported.</p></section>\n";
  html << "<p><a href=\"" << escape(in.map_file) << "\">" << escape(in.map_file)
       << "</a>: " << in.map_vertices << " vertices";
  if (in.map_triangles > 0) html << ", " << in.map_triangles << " triangles";
  html << "</p>\n<div class=\"previews\">\n";
  for (const std::string& file : in.previews) html << image(file, file, "preview");
  return html.str() + "</div></section>\n";
}

std::string timingsSection(const ReportInputs& in) {
  std::ostringstream html;
  html << "<section id=\"timings\"><h2>Timings</h2>\n";
  if (!in.timings) return html.str() + "<p>timings.json not available.</p></section>\n";
  html << keyValueTable("Whole run", *in.timings);
  const Json* stages = findMember(*in.timings, "stages");
  if (stages == nullptr || !stages->is_object()) return html.str() + "</section>\n";
  double longest = 1e-9;
  for (const auto& stage : *stages) {
    longest = std::max(longest, numberMember(stage, "p95_ms").value_or(0.0));
  }
  html << "<table class=\"stages\"><caption>Per stage</caption>\n<tr><th>stage</th><th>count</th>"
          "<th>median</th><th>p95</th><th>mean</th><th>max</th><th class=\"barcol\">"
          "median / p95</th></tr>\n";
  for (const auto& member : stages->items()) {
    const std::string& name = member.key();
    const Json& s = member.value();
    auto cell = [&](const char* key) {
      const Json* v = findMember(s, key);
      return v ? format(key, *v) : std::string("n/a");
    };
    const double median = numberMember(s, "median_ms").value_or(0.0),
                 p95 = numberMember(s, "p95_ms").value_or(0.0);
    char bars[200];
    std::snprintf(bars, sizeof(bars),
                  "<div class=\"bar p95\" style=\"width:%.1f%%\"><div class=\"bar median\" "
                  "style=\"width:%.1f%%\"></div></div>",
                  100.0 * p95 / longest, p95 > 0 ? 100.0 * median / p95 : 0.0);
    html << "<tr><th>" << escape(name) << "</th><td>" << cell("count") << "</td><td>"
         << cell("median_ms") << "</td><td>" << cell("p95_ms") << "</td><td>" << cell("mean_ms")
         << "</td><td>" << cell("max_ms") << "</td><td class=\"barcol\">" << bars << "</td></tr>\n";
  }
  return html.str() + "</table></section>\n";
}

std::string filesSection(const ReportInputs& in) {
  std::ostringstream html;
  html << "<section id=\"files\"><h2>Files</h2><p>";
  for (const char* name : {"trajectory.txt", "keyframes.txt", "frames.txt", "metrics.json",
                           "timings.json", "run.json", "config.yaml"}) {
    if (fs::exists(path(in, name))) html << "<a href=\"" << name << "\">" << name << "</a> ";
  }
  if (!in.map_file.empty())
    html << "<a href=\"" << escape(in.map_file) << "\">" << escape(in.map_file) << "</a>";
  html << "</p>\n";
  if (!in.notes.empty()) {
    html << "<ul class=\"notes\">\n";
    for (const std::string& note : in.notes) html << "<li>" << escape(note) << "</li>\n";
    html << "</ul>\n";
  }
  return html.str() + "</section>\n";
}

std::string timestampNow() {
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  char text[64];
  std::strftime(text, sizeof(text), "%Y-%m-%d %H:%M:%S", &local);
  return text;
}

}  // namespace

std::string writeHtmlReport(const std::string& out_dir, const std::string& sequence_name,
                            const std::string& ground_truth_path) {
  ReportInputs in;
  in.out_dir = out_dir;
  in.sequence_name = sequence_name;
  in.run = readOptionalJson(&in, "run.json");
  in.metrics = readOptionalJson(&in, "metrics.json");
  in.timings = readOptionalJson(&in, "timings.json");
  writePlots(ground_truth_path, &in);
  writePreviews(&in);

  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>dynamap: "
       << escape(sequence_name) << "</title>\n<style>\n"
       << kHtmlReportCss << "</style></head>\n<body>\n"
       << "<h1>dynamap run: " << escape(sequence_name) << "</h1>\n<p class=\"sub\">"
       << escape(fs::absolute(out_dir).string()) << " &middot; report written " << timestampNow()
       << "</p>\n"
       << runSection(in) << metricsSection(in) << plotsSection(in) << mapSection(in)
       << timingsSection(in) << filesSection(in) << "</body></html>\n";
  writeTextFileAtomic(path(in, "report.html"), html.str());
  std::string notes;
  for (const std::string& note : in.notes) notes += note + "\n";
  return notes;
}

}  // namespace dynamap
