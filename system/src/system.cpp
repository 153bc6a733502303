#include "dynamap/system.hpp"

#include <exception>
#include <filesystem>
#include <stdexcept>
#include <thread>
#include <utility>

#include "dynamap/core/dynamic/dynamic_motion_filter.hpp"
#include "dynamap/core/tracker.hpp"
#include "dynamap/mapping/backend_registry.hpp"
#include "dynamap/mapping/mapping_worker.hpp"
#include "dynamap/mapping/mask_lookahead.hpp"
#include "dynamap/system/map_store.hpp"
#include "frame_input.hpp"
#include "plugin_paths.hpp"

namespace dynamap {

struct System::Impl {
  SystemOptions options;
  PinholeCamera camera;
  TimingRecorder own_timings;
  TimingRecorder* timings = &own_timings;
  std::unique_ptr<MotionFilter> motion_filter;
  std::unique_ptr<Tracker> tracker;  // null with given poses
  std::unique_ptr<MappingWorker> mapper;
  FrameInput input;
  std::uint64_t next_keyframe_id = 0;
  std::string backend_name;
  SystemCounts counts;
  std::vector<TimedPose> given_trajectory;  // given poses only
  bool finished = false;
  // Mask look-ahead: the last keyframe waits for the masks of the next frames.
  int lookahead_frames = 0;
  int margin_px = 0;  // dynamic.mask_dilation_px
  double margin_behind_m = 0.0;
  std::shared_ptr<KeyframePacket> pending;
  int pending_seen = 0;
  std::vector<KeyframePacketPtr> last_mapped;  // released by finish()

  /// SystemOptions::load_map_dir: the tracker's map, and the backend's if it made the map.
  void loadMap(const std::string& dir);
  void pushKeyframe(KeyframePacketPtr kf);
  /// Adds what `frame`'s mask covers to the waiting keyframe's mask; hands it to the mapper
  /// once lookahead_frames frames have been seen.
  void lookAhead(const RgbdFrame& frame, const TrackingResult& tracked,
                 std::vector<KeyframePacketPtr>& mapped);
  void releasePending(std::vector<KeyframePacketPtr>& mapped);
  /// finish()'s parts: the last bundle adjustment, its poses to the mapper, the mapper's queue
  /// and last window.
  void finishTracking() {
    ScopedStageTimer timer(timings, "finish_tracking");
    tracker->finish();
  }
  void publishFinalPoses() {
    std::vector<PoseUpdate> final_poses;
    for (const auto& kf : tracker->keyframes()) final_poses.push_back({kf.id, kf.T_W_C});
    mapper->applyPoseUpdates(final_poses);
  }
  void drainMapper() {
    ScopedStageTimer timer(timings, "finish_mapping_drain");
    mapper->drain();
  }
};

void System::Impl::loadMap(const std::string& dir) {
  ScopedStageTimer timer(timings, "map_load");
  const std::filesystem::path folder(dir);
  MapStoreInfo info;
  MapContents contents = readMapStore((folder / kMapStoreFile).string(), camera, &info);
  counts.loaded_keyframes = contents.keyframes.size();
  // The dense map is the saved backend's files: another backend starts without it.
  if (info.backend == backend_name) {
    try {
      if (mapper->importMap((folder / "map").string())) {
        counts.loaded_map_elements = mapper->stats().elements;
      }
    } catch (const MappingError& e) {  // a saved file: the map's error, as the store's are
      throw MapFileError(e.what());
    }
  }
  tracker->loadMap(std::move(contents));
}

void System::Impl::pushKeyframe(KeyframePacketPtr kf) {
  if (!options.drop_keyframes_when_busy) {
    mapper->push(std::move(kf));
  } else if (!mapper->tryPush(std::move(kf))) {
    ++counts.mapper_dropped;
  }
}

void System::Impl::lookAhead(const RgbdFrame& frame, const TrackingResult& tracked,
                             std::vector<KeyframePacketPtr>& mapped) {
  if (!pending) return;
  if (tracked.status != FrameStatus::kLost && tracked.status != FrameStatus::kBadFrame) {
    ScopedStageTimer timer(timings, "mask_lookahead");
    // Only what the later frame saw moving: a person masked there for lack of evidence that
    // they stand still (held back) is no evidence against the keyframe's pixels.
    cv::Mat moving = tracked.dynamic_mask;
    if (!moving.empty() && !tracked.unconfirmed_mask.empty()) {
      moving = moving.clone();
      moving.setTo(0, tracked.unconfirmed_mask);
    }
    // The later mask's margin on its own background (the wall around that frame's outline of a
    // person) would land on the keyframe's background: it is trimmed as the keyframe's own is.
    moving = marginNotBehind(moving, frame.depth_m, margin_px, margin_behind_m);
    const cv::Mat later = maskSeenLater(camera, pending->depth_m, pending->T_W_C, frame.depth_m,
                                        tracked.T_W_C, moving);
    if (cv::countNonZero(later) > 0) {  // a new Mat: the tracker's keyframe keeps its own mask
      pending->dynamic_mask = pending->dynamic_mask.empty() ? later : pending->dynamic_mask | later;
    }
    // What a later frame saw moving for a reason of its own is no longer only held back there.
    if (!pending->held_mask.empty() && !moving.empty()) {
      cv::Mat moved = moving;
      if (!tracked.held_mask.empty()) moved = moving & ~tracked.held_mask;
      const cv::Mat later_moved = maskSeenLater(camera, pending->depth_m, pending->T_W_C,
                                                frame.depth_m, tracked.T_W_C, moved);
      if (cv::countNonZero(later_moved) > 0) pending->held_mask = pending->held_mask & ~later_moved;
    }
  }
  if (++pending_seen >= lookahead_frames) releasePending(mapped);
}

void System::Impl::releasePending(std::vector<KeyframePacketPtr>& mapped) {
  if (!pending) return;
  if (margin_behind_m > 0.0 && !pending->dynamic_mask.empty()) {
    ScopedStageTimer timer(timings, "mask_margin");
    pending->dynamic_mask =
        marginNotBehind(pending->dynamic_mask, pending->depth_m, margin_px, margin_behind_m);
  }
  KeyframePacketPtr kf = std::move(pending);
  pending.reset();
  mapped.push_back(kf);
  pushKeyframe(std::move(kf));
}

namespace {

cv::Mat maskOrZeros(const cv::Mat& mask, const cv::Size& size) {
  return mask.empty() ? cv::Mat(cv::Mat::zeros(size, CV_8UC1)) : mask;
}

}  // namespace

System::System(const AppConfig& config, SystemOptions options) : impl_(std::make_unique<Impl>()) {
  auto& s = *impl_;
  s.options = std::move(options);
  if (s.options.timings != nullptr) s.timings = s.options.timings;
  s.camera = config.resolvedCamera();
  s.lookahead_frames = config.mapping.mask_lookahead_frames;
  s.input = FrameInput(s.camera, config.camera.depth_scale);

  // Mapping backend first: an unknown backend or a bad parameter is an error before any work.
  std::vector<std::string> dirs = s.options.plugin_dirs;
  for (const auto& d : defaultPluginDirs()) dirs.push_back(d);
  const auto registry = BackendRegistry::scan(dirs);
  auto backend = registry.create(config.mapping.backend,
                                 paramsForBackend(config.mapping.params, config.mapping.backend));
  s.mapper = std::make_unique<MappingWorker>(
      std::move(backend), s.camera, config.mapping.static_points, s.options.mapping_queue_capacity,
      s.timings, s.options.drop_keyframes_when_busy ? 0 : s.options.mapping_thread_nice);
  s.motion_filter = std::move(s.options.motion_filter);
  if (s.options.given_poses && !s.options.load_map_dir.empty()) {
    throw std::invalid_argument("System: load_map_dir needs tracking (not with given poses)");
  }
  if (s.options.given_poses) return;
  if (!s.motion_filter) {
    s.motion_filter = makeMotionFilter(config.dynamic, s.camera, s.timings);
    // The margin trimmed is the one this motion filter grows; given masks have none.
    s.margin_px = config.dynamic.mask_dilation_px;
    s.margin_behind_m = config.mapping.mask_margin_behind_m;
  }
  s.tracker = std::make_unique<Tracker>(s.camera, config.tracking, s.timings);
  s.tracker->setMotionFilter(s.motion_filter.get());
  s.backend_name = config.mapping.backend;
  if (!s.options.load_map_dir.empty()) s.loadMap(s.options.load_map_dir);
}

std::unique_ptr<System> System::fromConfig(const std::string& config_path,
                                           const std::vector<std::string>& overrides,
                                           SystemOptions options, std::string* effective_yaml) {
  return std::make_unique<System>(loadAppConfig(config_path, overrides, effective_yaml),
                                  std::move(options));
}

System::~System() {
  try {
    finish();
  } catch (...) {  // a destructor must not throw; finish() already stopped what it could
  }
}

TrackOutput System::track(const cv::Mat& bgr, const cv::Mat& depth, double timestamp_s) {
  RgbdFrame frame = impl_->input.prepare(bgr, depth, timestamp_s);
  frame.index = impl_->counts.frames;
  return track(frame);
}

TrackOutput System::track(const RgbdFrame& frame) {
  auto& s = *impl_;
  if (!s.tracker) throw std::logic_error("System::track: built for given poses (mapWithPose)");
  if (s.finished) throw std::logic_error("System::track: called after finish()");
  ++s.counts.frames;
  const TrackingResult tracked = s.tracker->track(frame);
  TrackOutput out;
  out.status = tracked.status;
  out.T_W_C = tracked.T_W_C;
  out.dynamic_mask = maskOrZeros(tracked.dynamic_mask, frame.bgr.size());
  s.lookAhead(frame, tracked, out.mapped);
  if (tracked.is_keyframe && tracked.keyframe) {
    out.is_keyframe = true;
    out.keyframe = tracked.keyframe;
    s.releasePending(out.mapped);
    s.pending = std::make_shared<KeyframePacket>(*tracked.keyframe);
    s.pending_seen = 0;
    if (s.lookahead_frames == 0) s.releasePending(out.mapped);
  }
  const auto updates = s.tracker->takePoseUpdates();
  if (!updates.empty()) s.mapper->applyPoseUpdates(updates);
  return out;
}

void System::prefetch(const RgbdFrame& next) {
  auto& s = *impl_;
  if (s.tracker && s.motion_filter && !next.depth_m.empty()) s.motion_filter->prefetch(next);
}

void System::markBadFrame(double timestamp_s) {
  auto& s = *impl_;
  ++s.counts.frames;
  ++s.counts.bad_frames;
  if (s.tracker && !s.finished) s.tracker->markBadFrame(timestamp_s);
}

TrackOutput System::mapWithPose(const RgbdFrame& frame, const Eigen::Isometry3d& T_W_C,
                                const cv::Mat& mask) {
  auto& s = *impl_;
  if (s.tracker) throw std::logic_error("System::mapWithPose: needs SystemOptions::given_poses");
  if (s.finished) throw std::logic_error("System::mapWithPose: called after finish()");
  ++s.counts.frames;
  auto kf = std::make_shared<KeyframePacket>();
  kf->id = s.next_keyframe_id++;
  kf->timestamp_s = frame.timestamp_s;
  kf->T_W_C = T_W_C;
  kf->bgr = frame.bgr;
  kf->depth_m = frame.depth_m;
  kf->dynamic_mask = mask;
  s.given_trajectory.push_back({frame.timestamp_s, T_W_C});
  ++s.counts.keyframes;
  s.pushKeyframe(kf);
  TrackOutput out;
  out.mapped.push_back(kf);
  out.status = FrameStatus::kTracked;
  out.T_W_C = T_W_C;
  out.dynamic_mask = maskOrZeros(mask, frame.bgr.size());
  out.is_keyframe = true;
  out.keyframe = std::move(kf);
  return out;
}

std::vector<TimedPose> System::trajectory() const {
  if (!impl_->tracker) return impl_->given_trajectory;
  std::vector<TimedPose> poses;
  for (const auto& [t, T_W_C] : impl_->tracker->finalTrajectory()) poses.push_back({t, T_W_C});
  return poses;
}

std::vector<FrameStatus> System::frameStatuses() const {
  if (!impl_->tracker) {
    return std::vector<FrameStatus>(impl_->given_trajectory.size(), FrameStatus::kTracked);
  }
  return impl_->tracker->frameStatuses();
}

std::vector<TimedPose> System::keyframes() const {
  if (!impl_->tracker) return impl_->given_trajectory;
  std::vector<TimedPose> poses;
  for (const auto& kf : impl_->tracker->keyframes()) {
    if (!kf.culled) poses.push_back({kf.timestamp_s, kf.T_W_C});
  }
  return poses;
}

SystemCounts System::counts() const {
  const auto& s = *impl_;
  SystemCounts c = s.counts;
  if (s.tracker) {
    const TrackerStats stats = s.tracker->stats();
    c.tracked = stats.tracked;
    c.relocalized = stats.relocalized;
    c.posed_by_depth = stats.posed_by_depth;
    c.lost = stats.lost;
    c.keyframes = stats.keyframes - stats.culled_keyframes;
    c.culled_keyframes = stats.culled_keyframes;
  } else {
    c.tracked = s.given_trajectory.size();
  }
  const MapStats map = s.mapper->stats();
  c.mapped_keyframes = map.keyframes;
  c.map_elements = map.elements;
  return c;
}

void System::finish() {
  auto& s = *impl_;
  if (s.finished) return;
  s.finished = true;
  s.releasePending(s.last_mapped);
  if (s.tracker) {
    if (s.mapper->drainsAfterFinalPoses()) {
      // The mapper's last keyframes go in once, at their final poses, instead of going in at the
      // poses before and being moved again (50-100 ms each for octomap at 3 cm).
      s.finishTracking();
      s.publishFinalPoses();
      s.drainMapper();
    } else {
      // The mapper integrates its last keyframes on the other core while the last bundle
      // adjustment holds this one (it needs no pose; the final poses come after).
      std::exception_ptr drain_failed;
      std::thread drain([&] {
        try {
          s.drainMapper();
        } catch (...) {
          drain_failed = std::current_exception();
        }
      });
      try {
        s.finishTracking();
      } catch (...) {
        drain.join();
        throw;
      }
      drain.join();
      if (drain_failed) std::rethrow_exception(drain_failed);
      s.publishFinalPoses();
    }
  }
  ScopedStageTimer timer(s.timings, "finish_mapping");  // after the final poses
  s.mapper->finish();
}

std::unordered_map<std::uint64_t, cv::Mat> System::revisedMasks() const {
  if (!impl_->finished) return {};
  return impl_->mapper->revisedMasks();
}

std::vector<KeyframePacketPtr> System::takeLastMapped() {
  finish();
  return std::exchange(impl_->last_mapped, {});
}

void System::exportMap(const std::string& dir) {
  finish();
  std::filesystem::create_directories(dir);
  ScopedStageTimer timer(impl_->timings, "map_export");
  impl_->mapper->exportMap(dir);
}

void System::saveMap(const std::string& dir) {
  auto& s = *impl_;
  if (!s.tracker) throw std::logic_error("System::saveMap: not with given poses");
  finish();
  ScopedStageTimer timer(s.timings, "map_save");
  std::filesystem::create_directories(dir);
  const std::filesystem::path folder(dir);
  writeMapStore((folder / kMapStoreFile).string(), s.tracker->mapContents(), s.camera,
                s.backend_name);
  s.mapper->exportMap((folder / "map").string());
}

void System::exportMapSnapshot(const std::string& dir) {
  std::filesystem::create_directories(dir);
  impl_->mapper->waitIdle();
  ScopedStageTimer timer(impl_->timings, "map_snapshot");
  impl_->mapper->exportMap(dir);
}

const TimingRecorder& System::timings() const { return *impl_->timings; }
const MotionFilter* System::motionFilter() const { return impl_->motion_filter.get(); }

}  // namespace dynamap
