// Tracker + motion filter on teddy_dyn_dev without mapping (see track_harness.hpp): per frame
// what the tracker handed to filter() by ground-truth class, the mask scores, the drift; at
// the end the Horn-aligned ATE of the final trajectory and the timings.
#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>

#include "track_harness.hpp"

namespace fs = std::filesystem;
using namespace dynamap;

int main(int argc, char** argv) {
  CLI::App app{"track_bench: Tracker + motion filter on teddy_dyn_dev"};
  fs::path shared = fs::path(DYNAMAP_SOURCE_DIR) / ".." / "shared";
  int first = 0, count = 200;
  bool verbose = false;
  DynamicConfig dc;
  TrackerConfig tc;
  app.add_option("--shared", shared, "the shared data/models folder");
  app.add_option("--first", first, "first frame");
  app.add_option("--frames", count, "number of frames");
  app.add_option("--mode", dc.mode, "off | geometry | detector | both");
  app.add_option("--detector", dc.detector, "detector kind or none");
  app.add_option("--ba", tc.bundle_adjustment, "bundle adjustment (true|false)");
  app.add_option("--async", dc.detector_async, "dynamic.detector_async (true|false)");
  app.add_flag("--verbose", verbose, "one line per frame");
  CLI11_PARSE(app, argc, argv);
  resolveDynamicModelPaths(dc, (fs::path(DYNAMAP_SOURCE_DIR) / "config/default.yaml").string());

  const dynbench::DynSequence seq(shared / "data/dynamic/teddy_dyn_dev");
  TimingRecorder timings;
  auto inner = makeMotionFilter(dc, PinholeCamera{}, &timings);
  dynbench::SpyFilter spy(inner.get());
  Tracker tracker(PinholeCamera{}, tc, &timings);
  tracker.setMotionFilter(&spy);
  const int last = std::min<int>(static_cast<int>(seq.size()), first + count);
  double iou_sum = 0.0;
  int iou_n = 0, kfs = 0;
  long st = 0, st_m = 0, td = 0, td_m = 0;
  long cls[3] = {0, 0, 0}, dyn[3] = {0, 0, 0};
  Eigen::Isometry3d T_gt0 = Eigen::Isometry3d::Identity();
  bool have_gt0 = false;
  for (int i = first; i < last; ++i) {
    const dynbench::SequenceFrame f = seq.load(i);
    spy.setTruth(f.gt_mask);
    const TrackingResult r = tracker.track(f.frame);
    const auto& c = spy.last();
    const auto s = dynbench::scoreMask(r.dynamic_mask, f.gt_mask, f.teddy_mask);
    for (int k = 0; k < 3; ++k) cls[k] += c.by_class[k], dyn[k] += c.dynamic_by_class[k];
    if (r.is_keyframe) {
      ++kfs;
      if (s.moving_visible) iou_sum += s.iou, ++iou_n;
      st += s.standing_px, st_m += s.standing_masked_px, td += s.teddy_px;
      td_m += s.teddy_masked_px;
    }
    Eigen::Isometry3d T_gt;
    double err = -1.0;
    if (seq.gtPose(f.frame.timestamp_s, &T_gt)) {
      if (!have_gt0) T_gt0 = T_gt * r.T_W_C.inverse(), have_gt0 = true;
      err = ((T_gt0 * r.T_W_C).translation() - T_gt.translation()).norm();
    }
    if (verbose) {
      std::printf(
          "%3d %-11s kf %d | matches %3d mov %3d st %3d sc %3d | dyn mov %3d st %3d sc %3d %s| "
          "inl %3d | iou %.2f st %.2f teddy %.2f | drift %.3f\n",
          i, toString(r.status), r.is_keyframe, c.matches, c.by_class[0], c.by_class[1],
          c.by_class[2], c.dynamic_by_class[0], c.dynamic_by_class[1], c.dynamic_by_class[2],
          c.same_pair ? "" : "PAIR! ", r.inliers, s.iou, s.standing_masked, s.teddy_masked, err);
      if (const auto* dyn_filter = dynamic_cast<const DynamicMotionFilter*>(inner.get())) {
        const auto& dg = dyn_filter->lastDiagnostics();
        std::vector<double> res[3];
        for (std::size_t k = 0; k < dg.matches.cur_px.size() && k < dg.residual_px.size(); ++k) {
          res[dynbench::gtClass(f.gt_mask, dg.matches.cur_px[k])].push_back(dg.residual_px[k]);
        }
        auto med = [](const std::vector<double>& v) {
          return v.empty() ? -1.0 : percentile(v, 50);
        };
        std::printf("     model %d residual median moving %.1f standing %.1f scene %.1f\n",
                    static_cast<int>(dg.model), med(res[0]), med(res[1]), med(res[2]));
        for (const auto& o : dyn_filter->lastDiagnostics().objects) {
          const cv::Rect b = cv::Rect(o.detection.box) & cv::Rect(0, 0, 640, 480);
          if (b.area() == 0 || o.detection.class_id != 0) continue;
          std::printf(
              "     person %.2f pts %d dyn %d moving %d depth %.2f | box standing %.2f "
              "moving %.2f\n",
              o.detection.score, o.points, o.dynamic_points, o.moving, o.depth_m,
              cv::countNonZero(f.gt_mask(b) == 128) / double(b.area()),
              cv::countNonZero(f.gt_mask(b) == 255) / double(b.area()));
        }
      }
    }
  }
  tracker.finish();
  std::vector<Eigen::Vector3d> est, ref;
  for (const auto& [stamp, T] : tracker.finalTrajectory()) {
    Eigen::Isometry3d T_gt;
    if (!seq.gtPose(stamp, &T_gt)) continue;
    est.push_back(T.translation());
    ref.push_back(T_gt.translation());
  }
  auto med = [&](const char* stage) { return timings.stats(stage).median_ms; };
  std::printf(
      "mode=%s frames=%d ATE=%.4f m (%zu pairs) keyframes=%d kf meanIoU=%.3f standing=%.3f "
      "teddy=%.3f\n  matches mov %ld (dyn %.2f) standing %ld (dyn %.2f) scene %ld (dyn %.3f)\n"
      "  median ms: tracking %.1f lk %.1f motion_filter %.1f detector %.1f detector_wait %.1f "
      "(detections %zu)\n",
      dc.mode.c_str(), last - first, dynbench::ateRmse(est, ref), est.size(), kfs,
      iou_n ? iou_sum / iou_n : 0.0, st ? double(st_m) / st : 0.0, td ? double(td_m) / td : 0.0,
      cls[0], double(dyn[0]) / std::max(1L, cls[0]), cls[1], double(dyn[1]) / std::max(1L, cls[1]),
      cls[2], double(dyn[2]) / std::max(1L, cls[2]), med("tracking"), med("lk"),
      med("motion_filter"), med("detector"), med("detector_wait"), timings.stats("detector").count);
  return 0;
}
