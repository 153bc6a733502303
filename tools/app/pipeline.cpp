#include "pipeline.hpp"

#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <thread>

#include <opencv2/imgcodecs.hpp>

#include "dynamap/core/dynamic/dynamic_motion_filter.hpp"
#include "dynamap/core/tracker.hpp"
#include "dynamap/mapping/backend_registry.hpp"
#include "dynamap/mapping/mapping_worker.hpp"
#include "given_masks.hpp"
#include "image_io.hpp"
#include "interrupt.hpp"
#include "output_files.hpp"
#include "plugin_paths.hpp"
#include "pose_lookup.hpp"

namespace dynamap {

namespace fs = std::filesystem;

struct Pipeline::Stages {
  PinholeCamera camera;
  std::unique_ptr<MotionFilter> motion_filter;
  GivenMaskFilter* given_masks = nullptr;   // == motion_filter.get() with --masks
  std::unique_ptr<Tracker> tracker;         // null with --poses
  std::unique_ptr<PoseLookup> given_poses;  // set with --poses
  std::unique_ptr<MappingWorker> mapper;
  std::uint64_t next_keyframe_id = 0;
};

namespace {

constexpr std::size_t kMappingQueueCapacity = 16;
constexpr double kMaxRealtimeLagS =
    0.1;  ///< --realtime: skip a frame this late if a newer one waits

std::string stampName(const std::string& rgb_path) { return fs::path(rgb_path).stem().string(); }

class ProgressLine {
 public:
  ProgressLine(std::size_t total, bool quiet)
      : total_(total), quiet_(quiet), tty_(isatty(STDERR_FILENO) != 0), start_(Clock::now()) {}
  void update(std::size_t done) {
    if (quiet_ || total_ == 0) return;
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    const bool last = done == total_;
    const std::size_t step = std::max<std::size_t>(1, total_ / 10);
    if (tty_ ? (elapsed - last_print_s_ < 0.5 && !last) : (done % step != 0 && !last)) return;
    last_print_s_ = elapsed;
    const double fps = elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
    const double eta = fps > 0 ? static_cast<double>(total_ - done) / fps : 0.0;
    std::fprintf(stderr, "%sframe %zu/%zu  %.1f frames/s  ETA %.0f s%s", tty_ ? "\r" : "", done,
                 total_, fps, eta, tty_ && !last ? "" : "\n");
  }

 private:
  using Clock = std::chrono::steady_clock;
  std::size_t total_;
  bool quiet_;
  bool tty_;
  Clock::time_point start_;
  double last_print_s_ = -1.0;
};

}  // namespace

Pipeline::Pipeline(const RunOptions& options, const AppConfig& config, const TumSequence& sequence)
    : options_(options), config_(config), sequence_(sequence), stages_(std::make_unique<Stages>()) {
  auto& s = *stages_;
  s.camera = config_.resolvedCamera();
  if (fs::is_directory(fs::path(sequence_.directory()) / "mask")) {
    gt_masks_dir_ = (fs::path(sequence_.directory()) / "mask").string();
  }

  // Mapping backend first: an unknown backend or a bad parameter is an error before any work.
  const auto registry = BackendRegistry::scan(pluginSearchPath());
  auto backend = registry.create(config_.mapping.backend,
                                 paramsForBackend(config_.mapping.params, config_.mapping.backend));
  s.mapper =
      std::make_unique<MappingWorker>(std::move(backend), s.camera, config_.mapping.static_points,
                                      kMappingQueueCapacity, &timings_);

  if (!options_.masks_dir.empty()) {
    if (!fs::is_directory(options_.masks_dir)) {
      throw std::runtime_error(options_.masks_dir + ": --masks folder not found");
    }
    auto given = std::make_unique<GivenMaskFilter>(options_.masks_dir);
    s.given_masks = given.get();
    s.motion_filter = std::move(given);
  }
  if (!options_.poses_file.empty()) {
    s.given_poses = std::make_unique<PoseLookup>(readTrajectory(options_.poses_file));
    return;
  }
  if (!s.motion_filter) s.motion_filter = makeMotionFilter(config_.dynamic, s.camera, &timings_);
  s.tracker = std::make_unique<Tracker>(s.camera, config_.tracking, &timings_);
  s.tracker->setMotionFilter(s.motion_filter.get());
}

Pipeline::~Pipeline() = default;

RunResult Pipeline::run() {
  RunResult result;
  result.backend = config_.mapping.backend;
  result.mode = options_.realtime ? "realtime" : "offline";
  const auto start = std::chrono::steady_clock::now();
  try {
    processFrames(result);
  } catch (const std::exception& e) {
    result.status = "failed";
    result.error = e.what();
  }
  if (result.status == "complete" && interruptRequested()) result.status = "interrupted";
  try {
    finalize(result);
  } catch (const std::exception& e) {
    result.status = "failed";
    result.error += std::string(result.error.empty() ? "" : "; then: ") + e.what();
  }
  result.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

void Pipeline::processFrames(RunResult& result) {
  using Clock = std::chrono::steady_clock;
  const std::size_t total = sequence_.size();
  ProgressLine progress(total, options_.quiet);
  const auto& entries = sequence_.entries();
  const Clock::time_point start = Clock::now();
  const auto arrival = [&](std::size_t i) {  // --realtime: when frame i reaches us
    const double offset_s = entries[i].rgb_timestamp_s - entries.front().rgb_timestamp_s;
    return start +
           std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(offset_s));
  };
  for (std::size_t i = 0; i < total; ++i) {
    if (interruptRequested()) {
      result.status = "interrupted";
      std::fprintf(stderr, "\ninterrupted at frame %zu/%zu: writing what was computed\n", i, total);
      return;
    }
    if (options_.realtime) {
      std::this_thread::sleep_until(arrival(i));
      const double lag_s = std::chrono::duration<double>(Clock::now() - arrival(i)).count();
      if (lag_s > kMaxRealtimeLagS && i + 1 < total && Clock::now() >= arrival(i + 1)) {
        ++result.counts.skipped_realtime;  // a newer frame is waiting: this one is stale
        continue;
      }
    }
    processFrame(i, result);
    if (options_.realtime) {
      timings_.add("realtime_lag",
                   std::chrono::duration<double, std::milli>(Clock::now() - arrival(i)).count());
    }
    progress.update(i + 1);
  }
}

void Pipeline::pushKeyframe(KeyframePacketPtr kf, RunResult& result) {
  if (!options_.realtime) {
    stages_->mapper->push(std::move(kf));
  } else if (!stages_->mapper->tryPush(std::move(kf))) {
    ++result.counts.mapper_dropped;
  }
}

void Pipeline::processFrame(std::size_t index, RunResult& result) {
  auto& s = *stages_;
  const SequenceEntry& entry = sequence_.entries()[index];
  FrameLoad load = sequence_.load(index);
  ++result.counts.frames_read;
  if (!load.ok) {
    ++result.counts.bad_frames;
    std::fprintf(stderr, "\nbad frame %zu skipped: %s\n", index, load.error.c_str());
    if (s.tracker) s.tracker->markBadFrame(entry.rgb_timestamp_s);
    return;
  }
  const RgbdFrame& frame = load.frame;

  if (s.given_poses) {  // mapping from given poses: every frame with a pose is a keyframe
    const auto pose = s.given_poses->at(frame.timestamp_s);
    if (!pose) return;
    auto kf = std::make_shared<KeyframePacket>();
    kf->id = s.next_keyframe_id++;
    kf->timestamp_s = frame.timestamp_s;
    kf->T_W_C = *pose;
    kf->bgr = frame.bgr;
    kf->depth_m = frame.depth_m;
    if (s.given_masks) {
      s.given_masks->setNextRgbPath(entry.rgb_path);
      s.given_masks->beginFrame(frame);
      kf->dynamic_mask = s.given_masks->currentMask();
    }
    result.trajectory.push_back({frame.timestamp_s, *pose});
    result.frame_status.push_back("given");
    result.keyframes.push_back({frame.timestamp_s, *pose});
    ++result.counts.keyframes;
    pushKeyframe(kf, result);
    return;
  }

  if (s.given_masks) s.given_masks->setNextRgbPath(entry.rgb_path);
  const TrackingResult tracked = s.tracker->track(frame);
  if (tracked.is_keyframe && tracked.keyframe) {
    pushKeyframe(tracked.keyframe, result);
    if (!gt_masks_dir_.empty()) scoreKeyframeMask(entry, tracked, result);
    if (options_.save_masks) writeKeyframeMask(entry, tracked);
    if (options_.debug_images) writeDebugImage(entry, frame, tracked);
  }
  const auto updates = s.tracker->takePoseUpdates();
  if (!updates.empty()) s.mapper->applyPoseUpdates(updates);
}

void Pipeline::scoreKeyframeMask(const SequenceEntry& entry, const TrackingResult& tracked,
                                 RunResult& result) const {
  const std::string path = maskPathFor(gt_masks_dir_, entry.rgb_path, entry.rgb_timestamp_s);
  const cv::Mat gt = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (gt.empty() || gt.size() != tracked.keyframe->bgr.size()) return;  // no usable truth
  result.mask_scores.add(scoreMask(tracked.keyframe->dynamic_mask, gt));
}

void Pipeline::writeKeyframeMask(const SequenceEntry& entry, const TrackingResult& tracked) const {
  const fs::path dir = fs::path(options_.out_dir) / "masks";
  fs::create_directories(dir);
  cv::Mat mask = tracked.keyframe->dynamic_mask;
  if (mask.empty()) mask = cv::Mat::zeros(tracked.keyframe->bgr.size(), CV_8UC1);
  writeImageAtomic((dir / (stampName(entry.rgb_path) + ".png")).string(), mask);
}

void Pipeline::writeDebugImage(const SequenceEntry& entry, const RgbdFrame& frame,
                               const TrackingResult& tracked) const {
  const fs::path dir = fs::path(options_.out_dir) / "debug";
  fs::create_directories(dir);
  // Features static/dynamic, detections and the mask, as the paper's figures show them.
  const auto* computed = dynamic_cast<const DynamicMotionFilter*>(stages_->motion_filter.get());
  const cv::Mat picture =
      computed != nullptr
          ? drawMotionDebug(frame.bgr, computed->lastDiagnostics(), computed->classTable())
          : maskOverlay(frame.bgr, tracked.dynamic_mask);
  writeImageAtomic((dir / (stampName(entry.rgb_path) + ".jpg")).string(), picture);
}

void Pipeline::finalize(RunResult& result) {
  auto& s = *stages_;
  if (s.tracker) {
    s.tracker->finish();
    const auto trajectory = s.tracker->finalTrajectory();
    const auto statuses = s.tracker->frameStatuses();
    for (std::size_t i = 0; i < trajectory.size(); ++i) {
      result.trajectory.push_back({trajectory[i].first, trajectory[i].second});
      result.frame_status.push_back(i < statuses.size() ? toString(statuses[i]) : "unknown");
    }
    std::vector<PoseUpdate> final_poses;
    for (const auto& kf : s.tracker->keyframes()) {
      result.keyframes.push_back({kf.timestamp_s, kf.T_W_C});
      final_poses.push_back({kf.id, kf.T_W_C});
    }
    s.mapper->applyPoseUpdates(final_poses);
    const TrackerStats stats = s.tracker->stats();
    result.counts.tracked = stats.tracked;
    result.counts.relocalized = stats.relocalized;
    result.counts.lost = stats.lost;
    result.counts.keyframes = stats.keyframes;
  } else {
    result.counts.tracked = result.trajectory.size();
  }
  s.mapper->finish();
  result.counts.mapped_keyframes = s.mapper->stats().keyframes;
  result.map_dir = (fs::path(options_.out_dir) / "map").string();
  fs::create_directories(result.map_dir);
  s.mapper->exportMap(result.map_dir);
}

}  // namespace dynamap
