// Motion-area removal benchmark without the tracker (see dynamic_harness.hpp) and detector
// person recall with plain vs recall-oriented NMS on hand-labelled images.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include "dynamap/core/dynamic/dynamic_motion_filter.hpp"
#include "dynamic_harness.hpp"

namespace fs = std::filesystem;
using namespace dynamap;

namespace {

struct BoxRow {
  std::string image;
  cv::Rect2f box;
  bool difficult = false;
};

std::vector<BoxRow> readBoxes(const fs::path& csv) {
  std::ifstream in(csv);
  if (!in) throw std::runtime_error("cannot read " + csv.string());
  std::vector<BoxRow> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ss(line);
    BoxRow r;
    float x0, y0, x1, y1;
    int diff;
    ss >> r.image >> x0 >> y0 >> x1 >> y1 >> diff;
    r.box = cv::Rect2f(x0, y0, x1 - x0, y1 - y0);
    r.difficult = diff != 0;
    rows.push_back(r);
  }
  return rows;
}

void runRecall(const DynamicConfig& base, const fs::path& data, const fs::path& csv) {
  const auto rows = readBoxes(csv);
  std::map<std::string, std::vector<BoxRow>> by_image;
  for (const auto& r : rows) by_image[r.image].push_back(r);
  for (const std::string nms : {"plain", "recall"}) {
    DynamicConfig c = base;
    c.nms = nms;
    const ClassTable classes(c);
    auto det = makeObjectDetector(detectorOptions(c), classes);
    int hit_easy = 0, n_easy = 0, hit_all = 0, n_all = 0, n_dets = 0, false_pos = 0;
    for (const auto& [image, gts] : by_image) {
      const cv::Mat bgr = cv::imread((data / image).string());
      std::vector<Detection> persons;
      for (const auto& d : det->detect(bgr)) {
        if (d.class_id == 0) persons.push_back(d);
      }
      n_dets += static_cast<int>(persons.size());
      std::vector<bool> used(persons.size(), false);
      for (const auto& g : gts) {  // greedy: best unused detection with IoU >= 0.5
        int best = -1;
        float best_iou = 0.5f;
        for (std::size_t k = 0; k < persons.size(); ++k) {
          const float o = iou(g.box, persons[k].box);
          if (!used[k] && o >= best_iou) best_iou = o, best = static_cast<int>(k);
        }
        if (best >= 0) used[best] = true;
        n_all++, hit_all += best >= 0;
        if (!g.difficult) n_easy++, hit_easy += best >= 0;
      }
      for (std::size_t k = 0; k < persons.size(); ++k) false_pos += !used[k];
    }
    std::printf(
        "recall nms=%-6s persons(non-difficult) %d/%d = %.3f  all %d/%d = %.3f  person dets %d  "
        "unmatched dets %d\n",
        nms.c_str(), hit_easy, n_easy, double(hit_easy) / n_easy, hit_all, n_all,
        double(hit_all) / n_all, n_dets, false_pos);
  }
}

struct ModeSummary {
  double mean_iou = 0.0;
  double standing = 0.0, teddy = 0.0;
  int frames = 0;
};

/// One line per frame: scores, median residual per ground-truth class, the objects.
void printFrameDetails(int i, const dynbench::MaskScore& s, const dynbench::SequenceFrame& cur,
                       const FeatureMatches& matches, const DynamicMotionFilter& filter) {
  const auto& diag = filter.lastDiagnostics();
  std::vector<double> r[3];
  for (std::size_t k = 0; k < matches.cur_px.size() && k < diag.residual_px.size(); ++k) {
    const uchar g =
        cur.gt_mask.at<uchar>(cvRound(matches.cur_px[k].y), cvRound(matches.cur_px[k].x));
    r[g == 255 ? 0 : (g == 128 ? 1 : 2)].push_back(diag.residual_px[k]);
  }
  auto med = [](std::vector<double> v) { return v.empty() ? -1.0 : percentile(v, 50); };
  std::printf(
      "  frame %d iou %.2f standing %.2f teddy %.2f | median residual moving %.1f (%zu) "
      "standing %.1f (%zu) static %.1f (%zu)\n",
      i, s.iou, s.standing_masked, s.teddy_masked, med(r[0]), r[0].size(), med(r[1]), r[1].size(),
      med(r[2]), r[2].size());
  for (const auto& o : diag.objects) {
    const cv::Rect b = cv::Rect(o.detection.box) & cv::Rect(0, 0, 640, 480);
    const double st_share =
        b.area() ? cv::countNonZero(cur.gt_mask(b) == 128) / double(b.area()) : 0.0;
    const double mv_share =
        b.area() ? cv::countNonZero(cur.gt_mask(b) == 255) / double(b.area()) : 0.0;
    std::printf(
        "     obj %s %.2f pts %d dyn %d now %d moving %d depth %.2f | box standing %.2f moving "
        "%.2f\n",
        filter.classTable().name(o.detection.class_id).c_str(), o.detection.score, o.points,
        o.dynamic_points, o.moving_now, o.moving, o.depth_m, st_share, mv_share);
  }
  std::printf("     clusters %d\n", diag.clusters);
}

ModeSummary runMode(DynamicConfig c, const std::string& mode, const dynbench::DynSequence& seq,
                    int first, int count, const std::string& debug_dir, bool verbose) {
  c.mode = mode;
  DynamicMotionFilter filter(c, PinholeCamera{}, nullptr);
  TimingRecorder lk_timing;
  double iou_sum = 0.0;
  int iou_n = 0;
  long st = 0, st_m = 0, td = 0, td_m = 0;
  long pts[3] = {0, 0, 0}, pts_dyn[3] = {0, 0, 0};
  int model_count[4] = {0, 0, 0, 0};
  std::vector<double> residuals[3];
  dynbench::SequenceFrame prev = seq.load(first);
  const int last = std::min<int>(static_cast<int>(seq.size()) - 1, first + count);
  for (int i = first + 1; i <= last; ++i) {
    dynbench::SequenceFrame cur = seq.load(i);
    filter.beginFrame(cur.frame);
    ScopedStageTimer lk_timer(&lk_timing, "lk");
    const FeatureMatches matches = dynbench::trackLk(prev.gray, cur.gray);
    lk_timer.stop();
    const MotionFilterOutput out = filter.filter({&cur.frame, &prev.gray, &cur.gray, &matches});
    const auto s = dynbench::scoreMask(out.dynamic_mask, cur.gt_mask, cur.teddy_mask);
    if (s.moving_visible) iou_sum += s.iou, ++iou_n;
    const auto& diag = filter.lastDiagnostics();
    if (verbose) printFrameDetails(i, s, cur, matches, filter);
    ++model_count[static_cast<int>(diag.model)];
    for (std::size_t k = 0; k < matches.cur_px.size(); ++k) {
      const uchar g =
          cur.gt_mask.at<uchar>(cvRound(matches.cur_px[k].y), cvRound(matches.cur_px[k].x));
      const int cls = g == 255 ? 0 : (g == 128 ? 1 : 2);
      ++pts[cls];
      pts_dyn[cls] += diag.epipolar_dynamic[k];
      if (k < diag.residual_px.size()) residuals[cls].push_back(diag.residual_px[k]);
    }
    st += s.standing_px, st_m += s.standing_masked_px, td += s.teddy_px, td_m += s.teddy_masked_px;
    if (!debug_dir.empty()) {
      cv::Mat dbg = drawMotionDebug(cur.frame.bgr, filter.lastDiagnostics(), filter.classTable());
      cv::imwrite(debug_dir + "/" + mode + "_" + std::to_string(i) + ".jpg", dbg);
    }
    prev = std::move(cur);
  }
  ModeSummary m{iou_n ? iou_sum / iou_n : 0.0, st ? double(st_m) / st : 0.0,
                td ? double(td_m) / td : 0.0, last - first};
  auto med = [&](const char* stage) { return filter.timings().stats(stage).median_ms; };
  std::printf(
      "mode=%-8s frames=%d meanIoU=%.3f standing_masked=%.3f teddy_masked=%.3f | median ms: "
      "detector %.1f  detector_wait %.1f  epipolar %.1f  fusion %.1f  (lk %.1f)\n",
      mode.c_str(), m.frames, m.mean_iou, m.standing, m.teddy, med("detector"),
      med("detector_wait"), med("epipolar"), med("fusion"), lk_timing.stats("lk").median_ms);
  std::printf(
      "  epipolar flags: moving-person points %ld/%ld (%.3f), standing %ld/%ld (%.3f), static "
      "%ld/%ld "
      "(%.3f); frames none/F/H/rigid = %d/%d/%d/%d\n",
      pts_dyn[0], pts[0], double(pts_dyn[0]) / std::max(1L, pts[0]), pts_dyn[1], pts[1],
      double(pts_dyn[1]) / std::max(1L, pts[1]), pts_dyn[2], pts[2],
      double(pts_dyn[2]) / std::max(1L, pts[2]), model_count[0], model_count[1], model_count[2],
      model_count[3]);
  for (int c = 0; c < 3; ++c) {
    if (residuals[c].empty()) continue;
    std::printf("  residual px (%s): p25 %.2f p50 %.2f p75 %.2f p90 %.2f\n",
                c == 0 ? "moving" : (c == 1 ? "standing" : "static"), percentile(residuals[c], 25),
                percentile(residuals[c], 50), percentile(residuals[c], 75),
                percentile(residuals[c], 90));
  }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"dyn_bench: motion-area removal on teddy_dyn_dev and detector recall"};
  fs::path shared = fs::path(DYNAMAP_SOURCE_DIR) / ".." / "shared";
  std::vector<std::string> modes{"geometry", "detector", "both"};
  int first = 0, count = 199;
  std::string debug_dir, nms = "recall";
  bool recall_only = false, no_recall = false, verbose = false;
  app.add_flag("--verbose", verbose, "one line per frame");
  app.add_option("--shared", shared, "the shared data/models folder");
  app.add_option("--modes", modes, "modes to run")->delimiter(',');
  app.add_option("--first", first, "first frame");
  app.add_option("--frames", count, "number of frame pairs");
  app.add_option("--nms", nms, "plain | recall");
  app.add_option("--debug-dir", debug_dir, "write debug images here");
  app.add_flag("--recall-only", recall_only, "only the detector recall evaluation");
  app.add_flag("--no-recall", no_recall, "skip the detector recall evaluation");
  DynamicConfig config;
  app.add_option("--epipolar-threshold", config.epipolar_threshold_px,
                 "dynamic.epipolar_threshold_px");
  app.add_option("--reprojection-threshold", config.reprojection_threshold_px,
                 "dynamic.reprojection_threshold_px");
  app.add_option("--rigid-epipolar-threshold", config.rigid_epipolar_threshold_px,
                 "dynamic.rigid_epipolar_threshold_px");
  app.add_option("--boxed-fit-weight", config.boxed_fit_weight, "dynamic.boxed_fit_weight");
  app.add_option("--masked-fit-weight", config.masked_fit_weight, "dynamic.masked_fit_weight");
  app.add_option("--moving-ratio", config.moving_ratio, "dynamic.moving_ratio");
  app.add_option("--evidence-smoothing", config.evidence_smoothing, "dynamic.evidence_smoothing");
  app.add_option("--geometric-check", config.geometric_check, "pnp_reprojection | epipolar");
  app.add_option("--detector", config.detector, "yolo_darknet | nanodet_onnx | ... | none");
  app.add_option("--model-cfg", config.model_cfg, "dynamic.model_cfg");
  app.add_option("--model-weights", config.model_weights, "dynamic.model_weights");
  app.add_option("--input-size", config.input_width, "square detector input")
      ->each([&](const std::string&) { config.input_height = config.input_width; });
  CLI11_PARSE(app, argc, argv);
  try {
    config.nms = nms;
    resolveDynamicModelPaths(config,
                             (fs::path(DYNAMAP_SOURCE_DIR) / "config" / "default.yaml").string());
    if (!no_recall) {
      runRecall(config, shared / "data",
                fs::path(DYNAMAP_SOURCE_DIR) / "tests/dynamic/data/person_boxes.csv");
    }
    if (recall_only) return 0;
    if (!debug_dir.empty()) fs::create_directories(debug_dir);
    const dynbench::DynSequence seq(shared / "data/dynamic/teddy_dyn_dev");
    for (const auto& mode : modes) runMode(config, mode, seq, first, count, debug_dir, verbose);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dyn_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
