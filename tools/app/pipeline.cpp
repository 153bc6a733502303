#include "pipeline.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>

#include <opencv2/imgcodecs.hpp>

#include "dynamap/core/dynamic/dynamic_motion_filter.hpp"
#include "dynamap/system.hpp"
#include "frame_prefetch.hpp"
#include "given_masks.hpp"
#include "image_io.hpp"
#include "interrupt.hpp"
#include "output_files.hpp"
#include "pose_lookup.hpp"

namespace dynamap {

namespace fs = std::filesystem;

struct Pipeline::Stages {
  std::unique_ptr<System> system;
  GivenMaskFilter* given_masks = nullptr;   // the system's motion filter with --masks
  std::unique_ptr<PoseLookup> given_poses;  // set with --poses
};

namespace {

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
  if (fs::is_directory(fs::path(sequence_.directory()) / "mask")) {
    gt_masks_dir_ = (fs::path(sequence_.directory()) / "mask").string();
  }
  SystemOptions system_options;
  system_options.drop_keyframes_when_busy = options_.realtime;
  system_options.timings = &timings_;
  if (!options_.masks_dir.empty()) {
    if (!fs::is_directory(options_.masks_dir)) {
      throw std::runtime_error(options_.masks_dir + ": --masks folder not found");
    }
    auto given = std::make_unique<GivenMaskFilter>(options_.masks_dir);
    s.given_masks = given.get();
    system_options.motion_filter = std::move(given);
  }
  if (!options_.poses_file.empty()) {
    s.given_poses = std::make_unique<PoseLookup>(readTrajectory(options_.poses_file));
    system_options.given_poses = true;
  }
  system_options.load_map_dir = options_.load_map_dir;
  s.system = std::make_unique<System>(config_, std::move(system_options));
}

Pipeline::~Pipeline() = default;

namespace {

double processCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) { return t.tv_sec + 1e-6 * t.tv_usec; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

}  // namespace

RunResult Pipeline::run() {
  RunResult result;
  result.backend = config_.mapping.backend;
  result.mode = options_.realtime ? "realtime" : "offline";
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start_s = processCpuSeconds();
  try {
    processFrames(result);
  } catch (const std::exception& e) {
    result.status = "failed";
    result.error = e.what();
  }
  if (result.status == "complete" && interruptRequested()) result.status = "interrupted";
  const auto finish_start = std::chrono::steady_clock::now();
  try {
    finalize(result);
  } catch (const std::exception& e) {
    result.status = "failed";
    result.error += std::string(result.error.empty() ? "" : "; then: ") + e.what();
  }
  const auto end = std::chrono::steady_clock::now();
  result.wall_time_s = std::chrono::duration<double>(end - start).count();
  result.finish_s = std::chrono::duration<double>(end - finish_start).count();
  result.cpu_s = processCpuSeconds() - cpu_start_s;
  try {
    scoreKeyframeMasks(result);
  } catch (const std::exception& e) {
    result.status = "failed";
    result.error += std::string(result.error.empty() ? "" : "; then: ") + e.what();
  }
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
  // Offline, the detector may start on the next frame as soon as it is read (it is the next
  // one tracked); --realtime may skip frames, so it does not read ahead.
  auto& s = *stages_;
  FramePrefetcher frames(
      sequence_, options_.realtime || s.given_poses
                     ? std::function<void(const RgbdFrame&)>()
                     : [&s](const RgbdFrame& next) { s.system->prefetch(next); });
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
    const auto read_start = Clock::now();
    if (options_.realtime && i + 1 < total) {  // the last frame is tracked however late
      timings_.add("realtime_wait",
                   std::chrono::duration<double, std::milli>(read_start - arrival(i)).count());
    }
    FrameLoad load = frames.take(i);
    timings_.add("frame_read",
                 std::chrono::duration<double, std::milli>(Clock::now() - read_start).count());
    processFrame(i, load, result);
    if (options_.realtime) {
      timings_.add("realtime_lag",
                   std::chrono::duration<double, std::milli>(Clock::now() - arrival(i)).count());
    }
    progress.update(i + 1);
  }
}

void Pipeline::processFrame(std::size_t index, const FrameLoad& load, RunResult& result) {
  auto& s = *stages_;
  const SequenceEntry& entry = sequence_.entries()[index];
  ++result.counts.frames_read;
  if (!load.ok) {
    ++result.counts.bad_frames;
    std::fprintf(stderr, "\nbad frame %zu skipped: %s\n", index, load.error.c_str());
    s.system->markBadFrame(entry.rgb_timestamp_s);
    return;
  }
  const RgbdFrame& frame = load.frame;

  if (s.given_poses) {  // mapping from given poses: every frame with a pose is a keyframe
    const auto pose = s.given_poses->at(frame.timestamp_s);
    if (!pose) return;
    cv::Mat mask;
    if (s.given_masks) {
      s.given_masks->setNextRgbPath(entry.rgb_path);
      s.given_masks->beginFrame(frame);
      mask = s.given_masks->currentMask();
    }
    s.system->mapWithPose(frame, *pose, mask);
    return;
  }

  if (s.given_masks) s.given_masks->setNextRgbPath(entry.rgb_path);
  const TrackOutput tracked = s.system->track(frame);
  if (options_.debug_images) logObjects(entry);
  if (tracked.is_keyframe) {
    keyframe_entry_[tracked.keyframe->id] = index;
    if (!gt_masks_dir_.empty() && !tracked.keyframe->dynamic_mask.empty())
      tracker_masks_.emplace_back(index, tracked.keyframe->dynamic_mask);
    if (options_.debug_images) writeDebugImage(entry, frame, tracked);
  }
  mappedKeyframes(tracked.mapped);
}

Pipeline::KeptMask::KeptMask(std::size_t entry_index, const cv::Mat& mask) : entry(entry_index) {
  if (!mask.empty()) cv::imencode(".png", mask, png, {cv::IMWRITE_PNG_COMPRESSION, 1});
}

cv::Mat Pipeline::KeptMask::decoded() const {
  return png.empty() ? cv::Mat() : cv::imdecode(png, cv::IMREAD_UNCHANGED);
}

void Pipeline::mappedKeyframes(const std::vector<KeyframePacketPtr>& mapped) {
  for (const KeyframePacketPtr& kf : mapped) {
    const auto it = keyframe_entry_.find(kf->id);
    if (it == keyframe_entry_.end()) continue;
    const std::size_t index = it->second;
    const SequenceEntry& entry = sequence_.entries()[index];
    mapped_entry_[kf->id] = index;
    keyframe_entry_.erase(it);
    cv::Mat mask = kf->dynamic_mask;
    if (mask.empty()) mask = cv::Mat::zeros(kf->bgr.size(), CV_8UC1);
    if (!gt_masks_dir_.empty()) mapped_masks_[kf->id] = KeptMask(index, mask);
    if (options_.save_masks) writeKeyframeMask(entry, mask, kf->bgr.size());
  }
}

void Pipeline::revisedKeyframeMasks() {
  for (const auto& [id, mask] : stages_->system->revisedMasks()) {
    const auto it = mapped_entry_.find(id);
    if (it == mapped_entry_.end()) continue;
    const SequenceEntry& entry = sequence_.entries()[it->second];
    if (!gt_masks_dir_.empty()) mapped_masks_[id] = KeptMask(it->second, mask);
    if (options_.save_masks) writeKeyframeMask(entry, mask, mask.size());
  }
}

void Pipeline::scoreKeyframeMasks(RunResult& result) const {
  if (gt_masks_dir_.empty()) return;
  std::unordered_map<std::size_t, cv::Mat> truth;  // entry -> its ground-truth mask, read once
  const auto score = [&](std::size_t index, const cv::Mat& mask) -> std::optional<MaskFrameScore> {
    auto it = truth.find(index);
    if (it == truth.end()) {
      const SequenceEntry& entry = sequence_.entries()[index];
      const std::string path = maskPathFor(gt_masks_dir_, entry.rgb_path, entry.rgb_timestamp_s);
      it = truth.emplace(index, cv::imread(path, cv::IMREAD_GRAYSCALE)).first;
    }
    const cv::Mat& gt = it->second;
    if (mask.empty() || gt.empty() || gt.size() != mask.size()) return std::nullopt;  // no truth
    return scoreMask(mask, gt);
  };
  for (const KeptMask& kept : tracker_masks_) {
    if (const auto s = score(kept.entry, kept.decoded())) result.tracker_mask_scores.add(*s);
  }
  for (const auto& [id, kept] : mapped_masks_) {
    if (const auto s = score(kept.entry, kept.decoded())) result.mask_scores.add(*s);
  }
}

void Pipeline::writeKeyframeMask(const SequenceEntry& entry, const cv::Mat& mask,
                                 const cv::Size& size) const {
  const fs::path dir = fs::path(options_.out_dir) / "masks";
  fs::create_directories(dir);
  const cv::Mat out = mask.empty() ? cv::Mat(cv::Mat::zeros(size, CV_8UC1)) : mask;
  writeImageAtomic((dir / (stampName(entry.rgb_path) + ".png")).string(), out);
}

void Pipeline::writeDebugImage(const SequenceEntry& entry, const RgbdFrame& frame,
                               const TrackOutput& tracked) const {
  const fs::path dir = fs::path(options_.out_dir) / "debug";
  fs::create_directories(dir);
  // Features static/dynamic, detections and the mask, as the paper's figures show them.
  const auto* computed = dynamic_cast<const DynamicMotionFilter*>(stages_->system->motionFilter());
  const cv::Mat picture =
      computed != nullptr
          ? drawMotionDebug(frame.bgr, computed->lastDiagnostics(), computed->classTable())
          : maskOverlay(frame.bgr, tracked.dynamic_mask);
  writeImageAtomic((dir / (stampName(entry.rgb_path) + ".jpg")).string(), picture);
}

void Pipeline::logObjects(const SequenceEntry& entry) {
  const auto* computed = dynamic_cast<const DynamicMotionFilter*>(stages_->system->motionFilter());
  if (computed == nullptr) return;
  const fs::path dir = fs::path(options_.out_dir) / "debug";
  fs::create_directories(dir);
  std::ofstream log(dir / "objects.tsv", object_log_started_ ? std::ios::app : std::ios::trunc);
  if (!object_log_started_) log << objectLogHeader();
  object_log_started_ = true;
  log << objectLogLines(entry.rgb_timestamp_s, computed->lastDiagnostics(), computed->classTable());
}

void Pipeline::finalize(RunResult& result) {
  System& system = *stages_->system;
  system.finish();
  mappedKeyframes(system.takeLastMapped());
  revisedKeyframeMasks();
  const auto trajectory = system.trajectory();
  const auto statuses = system.frameStatuses();
  const bool given = stages_->given_poses != nullptr;
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    result.trajectory.push_back(trajectory[i]);
    result.frame_status.push_back(given                 ? "given"
                                  : i < statuses.size() ? toString(statuses[i])
                                                        : "unknown");
  }
  result.keyframes = system.keyframes();
  result.map_dir = (fs::path(options_.out_dir) / "map").string();
  // The map first (a backend counts its elements as it exports); the counts even if it fails.
  std::exception_ptr export_failed;
  try {
    system.exportMap(result.map_dir);
  } catch (...) {
    export_failed = std::current_exception();
  }
  const SystemCounts counts = system.counts();
  result.counts.tracked = counts.tracked;
  result.counts.relocalized = counts.relocalized;
  result.counts.posed_by_depth = counts.posed_by_depth;
  result.counts.lost = counts.lost;
  result.counts.keyframes = counts.keyframes;
  result.counts.culled_keyframes = counts.culled_keyframes;
  result.counts.mapped_keyframes = counts.mapped_keyframes;
  result.counts.mapper_dropped = counts.mapper_dropped;
  result.counts.loaded_keyframes = counts.loaded_keyframes;
  result.counts.loaded_map_elements = counts.loaded_map_elements;
  if (export_failed) std::rethrow_exception(export_failed);
  if (!options_.save_map_dir.empty()) system.saveMap(options_.save_map_dir);  // after the outputs
}

}  // namespace dynamap
