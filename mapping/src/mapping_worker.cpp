#include "dynamap/mapping/mapping_worker.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#ifdef __linux__
#include <sys/resource.h>
#include <unistd.h>
#endif

#include "dynamap/mapping/in_two.hpp"

namespace dynamap {
namespace {

/// The held revision's confirmed-static and moved points: one per square of pixels as wide as a
/// voxel at this depth (TUM's camera, 3 cm: 4 x 4 pixels; the 27 voxels around a held pixel still
/// reach a point up to here).
constexpr double kHeldPointSpacingDepthM = 4.0;
int heldStridePx(const PinholeCamera& camera, double voxel_m) {
  return std::max(1, static_cast<int>(voxel_m * camera.fx / kHeldPointSpacingDepthM));
}

bool movedBeyond(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double trans_m,
                 double rot_rad) {
  const Eigen::Isometry3d delta = a.inverse() * b;
  const double angle = Eigen::AngleAxisd(delta.rotation()).angle();
  return delta.translation().norm() > trans_m || std::fabs(angle) > rot_rad;
}

}  // namespace

MappingWorker::MappingWorker(std::unique_ptr<MapBackend> backend, const PinholeCamera& camera,
                             const StaticPointsOptions& options, std::size_t queue_capacity,
                             TimingRecorder* timings, int thread_nice)
    : backend_(std::move(backend)),
      camera_(camera),
      options_(options),
      capacity_(std::max<std::size_t>(1, queue_capacity)),
      thread_nice_(thread_nice),
      timings_(timings) {
  if (!backend_) throw MappingError("MappingWorker: null backend");
  if (backend_->fusesViews()) options_.mask_dilation_px = options_.fused_mask_dilation_px;
  thread_ = std::thread([this] { run(); });
}

MappingWorker::~MappingWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  not_empty_.notify_all();
  not_full_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void MappingWorker::push(KeyframePacketPtr kf) {
  std::unique_lock<std::mutex> lock(mutex_);
  const std::size_t limit = pushLimit();
  if (queue_.size() >= limit && !stopping_) {  // the tracker waits for the mapper
    ScopedStageTimer wait(timings_, "mapping_wait");
    not_full_.wait(lock, [&] { return queue_.size() < limit || stopping_; });
  }
  if (stopping_) return;
  queue_.push_back(std::move(kf));
  ++pushed_;
  lock.unlock();
  not_empty_.notify_one();
}

bool MappingWorker::tryPush(KeyframePacketPtr kf) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (stopping_ || queue_.size() >= capacity_) {
    ++dropped_;
    return false;
  }
  queue_.push_back(std::move(kf));
  ++pushed_;
  lock.unlock();
  not_empty_.notify_one();
  return true;
}

void MappingWorker::applyPoseUpdates(const std::vector<PoseUpdate>& updates) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& u : updates) pending_updates_.emplace_back(pushed_, u);
  }
  not_empty_.notify_one();
}

void MappingWorker::run() {
#ifdef __linux__
  // This thread only (Linux applies a thread id's nice to that thread). A refusal changes nothing
  // but the scheduling, so it is ignored.
  if (thread_nice_ != 0) (void)setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), thread_nice_);
#endif
  for (;;) {
    KeyframePacketPtr kf;
    std::vector<PoseUpdate> updates;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      // An update published after the n-th keyframe was queued is applied after that keyframe
      // and before the next: the same order as the tracker's, whatever the threads' timing.
      const auto due = [this] {
        return !pending_updates_.empty() && pending_updates_.front().first <= taken_;
      };
      not_empty_.wait(lock, [&] { return stopping_ || !queue_.empty() || due(); });
      while (due()) {
        updates.push_back(pending_updates_.front().second);
        pending_updates_.pop_front();
      }
      if (updates.empty() && !queue_.empty()) {
        kf = std::move(queue_.front());
        queue_.pop_front();
        ++taken_;
      }
      if (!kf && updates.empty() && stopping_) break;
      busy_ = true;
    }
    not_full_.notify_all();
    {
      std::lock_guard<std::mutex> lock(backend_mutex_);
      for (const auto& u : updates) applyUpdateLocked(u);
      if (kf) advanceWindow(std::move(kf), false);
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
    }
    idle_.notify_all();
  }
  std::lock_guard<std::mutex> lock(backend_mutex_);
  advanceWindow(nullptr, true);
}

void MappingWorker::advanceWindow(KeyframePacketPtr kf, bool flush) {
  const FreeSpaceOptions& fs = options_.free_space;
  const std::size_t n = fs.enabled ? static_cast<std::size_t>(std::max(0, fs.neighbours)) : 0;
  if (kf) {
    WindowEntry e;
    if (n > 0) e.view = makeFreeSpaceView(kf->depth_m, kf->T_W_C);
    e.kf = std::move(kf);
    window_.push_back(std::move(e));
  }
  for (std::size_t i = 0; i < window_.size(); ++i) {
    if (window_[i].integrated) continue;
    if (!flush && window_.size() - i - 1 < n) break;  // wait for the later neighbours
    cv::Mat flagged;
    if (n > 0) {
      ScopedStageTimer timer(timings_, "mapping_free_space");
      std::vector<const FreeSpaceView*> others;
      for (std::size_t j = (i > n ? i - n : 0); j < std::min(window_.size(), i + n + 1); ++j) {
        if (j != i) others.push_back(&window_[j].view);
      }
      const KeyframePacket& k = *window_[i].kf;
      flagged = freeSpaceViolations(camera_, k.depth_m, k.T_W_C, others, fs, k.dynamic_mask);
    }
    integratePacket(*window_[i].kf, flagged);
    window_[i].integrated = true;
  }
  if (!deferred()) judgeReadyLocked(false);
  // Keep the n integrated keyframes before the first waiting one.
  std::size_t integrated = 0;
  while (integrated < window_.size() && window_[integrated].integrated) ++integrated;
  while (integrated > n) {
    window_.pop_front();
    --integrated;
  }
}

void MappingWorker::applyUpdateLocked(const PoseUpdate& update) {
  auto it = records_.find(update.keyframe_id);
  if (it == records_.end()) {  // the keyframe is still queued: apply when it is integrated
    early_updates_[update.keyframe_id] = update.T_W_C;
    return;
  }
  it->second.T_current = update.T_W_C;
  if (it->second.integrated) backend_->updatePose(update.keyframe_id, update.T_W_C);
  if (it->second.supplemented)
    backend_->updatePose(update.keyframe_id | kSupplementBit, update.T_W_C);
}

void MappingWorker::integratePacket(const KeyframePacket& kf, const cv::Mat& extra_mask) {
  ScopedStageTimer timer(timings_, "mapping_keyframe");
  cv::Mat mask = kf.dynamic_mask;
  if (!extra_mask.empty() && cv::countNonZero(extra_mask) > 0) {
    mask = mask.empty() ? extra_mask : cv::max(mask, extra_mask);
  }
  KeyframeRecord rec;
  rec.timestamp_s = kf.timestamp_s;
  rec.T_integrated = kf.T_W_C;
  rec.T_current = kf.T_W_C;
  staticDepth(kf.depth_m, mask, options_).convertTo(rec.depth_u16, CV_16UC1, kDepthUnitsPerM);
  rec.bgr = kf.bgr;  // shared, immutable packet data
  if (options_.visibility.enabled)
    rec.view =
        makeVisibilityView(kf.depth_m, kf.dynamic_mask, options_.visibility, kf.moved_object_mask);
  if (options_.held_revision_voxel_m > 0.0) {
    const int stride = heldStridePx(camera_, options_.held_revision_voxel_m);
    rec.held.confirmed_C = maskPoints(camera_, kf.depth_m, kf.confirmed_mask, stride);
    if (!kf.dynamic_mask.empty()) {
      const cv::Mat moved =
          kf.held_mask.empty() ? kf.dynamic_mask : kf.dynamic_mask & ~kf.held_mask;
      rec.held.moved_C = maskPoints(camera_, kf.depth_m, moved, stride);
    }
    if (!kf.held_mask.empty() && !kf.dynamic_mask.empty()) {
      rec.held.held = kf.held_mask & kf.dynamic_mask;
      kf.depth_m.convertTo(rec.held_depth_u16, CV_16UC1, kDepthUnitsPerM);
      rec.dynamic_mask = kf.dynamic_mask;  // shared, immutable packet data
      rec.extra_mask = extra_mask;
    }
  }
  if (records_.emplace(kf.id, std::move(rec)).second) {
    order_.push_back(kf.id);
    if (!deferred()) judge_.push_back(kf.id);
    if (first_keyframe_s_ < 0.0) first_keyframe_s_ = kf.timestamp_s;
  }
  const auto early = early_updates_.find(kf.id);
  if (early != early_updates_.end()) {
    const PoseUpdate update{kf.id, early->second};
    early_updates_.erase(early);
    applyUpdateLocked(update);
  }
}

bool MappingWorker::removeSeenThroughLocked() {
  if (!options_.visibility.enabled || order_.empty()) return false;
  ScopedStageTimer timer(timings_, "mapping_visibility");
  std::vector<VisibilityKeyframe> keyframes;
  keyframes.reserve(order_.size());
  for (const std::uint64_t id : order_) {
    KeyframeRecord& rec = records_.at(id);
    VisibilityKeyframe k;
    k.static_depth = &rec.depth_u16;
    k.metres_per_unit = 1.0 / kDepthUnitsPerM;
    k.T_W_C = rec.T_current;
    k.view = &rec.view;
    k.timestamp_s = rec.timestamp_s;
    keyframes.push_back(k);
  }
  visibility_ = removeSeenThrough(camera_, keyframes, options_.visibility);
  addVisibilityTimings(visibility_);
  return visibility_.removed_pixels > 0;
}

bool MappingWorker::reviseHeldLocked() {
  if (options_.held_revision_voxel_m <= 0.0 || order_.empty()) return false;
  ScopedStageTimer timer(timings_, "mapping_held_revision");
  prepareHeldLocked();
  std::vector<HeldKeyframe> keyframes;
  keyframes.reserve(order_.size());
  for (const std::uint64_t id : order_) {
    KeyframeRecord& rec = records_.at(id);
    rec.held.T_W_C = rec.T_current;
    keyframes.push_back(std::move(rec.held));
  }
  const std::vector<cv::Mat> hits = heldConfirmedElsewhere(
      camera_, keyframes, options_.held_revision_voxel_m, options_.held_revision_min_keyframes);
  std::vector<cv::Mat> revised(order_.size());
  inTwo([&](int h) {  // every other keyframe: each thread writes only its keyframes' records
    for (std::size_t i = static_cast<std::size_t>(h); i < order_.size(); i += 2) {
      revised[i] = reviseOneLocked(order_[i], hits[i], keyframes[i].depth_m, false);
    }
  });
  bool any = false;
  for (std::size_t i = 0; i < order_.size(); ++i) {
    if (revised[i].empty()) continue;
    revised_masks_[order_[i]] = revised[i];
    any = true;
  }
  return any;
}

// The held depths as metres: no pose needed, so drain() does it beside the last bundle
// adjustment. Each keyframe once (its 16-bit copy is released).
void MappingWorker::prepareHeldLocked() {
  if (options_.held_revision_voxel_m <= 0.0) return;
  const auto convert = [this](std::size_t i) {
    KeyframeRecord& rec = records_.at(order_[i]);
    if (rec.held_depth_u16.empty()) return;
    rec.held_depth_u16.convertTo(rec.held.depth_m, CV_32FC1, 1.0 / kDepthUnitsPerM);
    rec.held_depth_u16.release();
  };
  for (std::size_t i = 0; i < order_.size(); ++i) convert(i);
}

std::unordered_map<std::uint64_t, cv::Mat> MappingWorker::revisedMasks() const {
  std::lock_guard<std::mutex> lock(backend_mutex_);
  return revised_masks_;
}

void MappingWorker::recordPointsLocked(std::uint64_t id, StaticPoints& sp) const {
  const KeyframeRecord& rec = records_.at(id);
  rec.depth_u16.convertTo(sp.static_depth_m, CV_32FC1, 1.0 / kDepthUnitsPerM);
  if (backend_->needsPoints()) {
    backProjectDepth(camera_, rec.bgr, sp.static_depth_m, options_.stride, &sp.points_C,
                     &sp.colors);
  }
}

void MappingWorker::rebuildIfNeeded(bool force) {
  if (!force && backend_->poseUpdateMode() != PoseUpdateMode::kReintegrate) return;
  // Half a cell of the backend's map, at least kReintegrateTranslationM (and the rotation in
  // proportion): a smaller move changes little that the cells can hold.
  const double scale = std::max(1.0, 0.5 * backend_->cellSizeM() / kReintegrateTranslationM);
  std::vector<std::uint64_t> moved;
  for (const std::uint64_t id : order_) {
    const KeyframeRecord& rec = records_.at(id);
    if (movedBeyond(rec.T_integrated, rec.T_current, scale * kReintegrateTranslationM,
                    scale * kReintegrateRotationRad)) {
      moved.push_back(id);
    }
  }
  if (!force && moved.empty()) return;
  // Taking a keyframe out and in again costs two integrations: cheaper than all of them while
  // fewer than half moved.
  if (!force && backend_->canDeintegrate() && 2 * moved.size() < order_.size()) {
    moveKeyframesLocked(moved);
    return;
  }
  ScopedStageTimer timer(timings_, "mapping_rebuild");
  if (!deferred()) backend_->reset();  // deferred: the backend has had nothing yet
  supplements_ = 0;                    // a record's depth holds its supplement
  // Keyframes are integrated in their order on this thread while the next one's points are made
  // on the other (it reads only its own record).
  const auto integrate = [this](std::uint64_t id, const StaticPoints& sp) {
    KeyframeRecord& rec = records_.at(id);
    std::optional<ScopedStageTimer> timer;  // deferred: the backend's cost per keyframe
    if (deferred()) timer.emplace(timings_, "mapping_integrate");
    backend_->integrate(keyframeView(id, rec.timestamp_s, rec.T_current, camera_, rec.bgr, sp));
    rec.T_integrated = rec.T_current;
    rec.integrated = true;
  };
  StaticPoints sp[2];
  if (!order_.empty()) recordPointsLocked(order_.front(), sp[0]);
  for (std::size_t i = 0; i < order_.size(); ++i) {
    inTwo([&](int h) {
      if (h == 1) {
        integrate(order_[i], sp[i % 2]);
      } else if (i + 1 < order_.size()) {
        recordPointsLocked(order_[i + 1], sp[(i + 1) % 2]);
      }
    });
  }
  reintegrated_ = order_.size();
}

// A keyframe with a supplement (held pixels confirmed later) went in as two views and comes out
// as one (its depth holds both): the cells both saw keep a little of the first.
void MappingWorker::moveKeyframesLocked(const std::vector<std::uint64_t>& ids) {
  ScopedStageTimer timer(timings_, "mapping_move");
  for (const std::uint64_t id : ids) {
    KeyframeRecord& rec = records_.at(id);
    if (!rec.integrated) continue;  // it goes in with its current pose
    ScopedStageTimer one(timings_, "mapping_move_keyframe");
    StaticPoints sp;
    recordPointsLocked(id, sp);
    backend_->moveKeyframe(
        keyframeView(id, rec.timestamp_s, rec.T_integrated, camera_, rec.bgr, sp),
        keyframeView(id, rec.timestamp_s, rec.T_current, camera_, rec.bgr, sp));
    rec.T_integrated = rec.T_current;
    ++reintegrated_;
  }
}

void MappingWorker::drain() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  not_empty_.notify_all();
  not_full_.notify_all();
  {
    std::lock_guard<std::mutex> lock(join_mutex_);
    if (thread_.joinable()) thread_.join();
  }
  std::lock_guard<std::mutex> lock(backend_mutex_);
  if (drained_) return;
  drained_ = true;
  if (deferred()) {
    prepareHeldLocked();
  } else {
    judgeReadyLocked(true);  // the last keyframes, with the poses before the final ones
  }
}

void MappingWorker::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (finished_) return;
    finished_ = true;
  }
  drain();
  std::vector<PoseUpdate> late;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& u : pending_updates_) late.push_back(u.second);  // after the last round
    pending_updates_.clear();
  }
  std::lock_guard<std::mutex> lock(backend_mutex_);
  for (const auto& u : late) applyUpdateLocked(u);
  if (!deferred()) {
    rebuildIfNeeded(false);  // a volumetric backend whose keyframes moved
    return;
  }
  reviseHeldLocked();
  removeSeenThroughLocked();
  rebuildIfNeeded(true);
}

void MappingWorker::waitIdle() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return (queue_.empty() && !busy_) || stopping_; });
}

void MappingWorker::exportMap(const std::string& dir) {
  std::lock_guard<std::mutex> lock(backend_mutex_);
  backend_->exportMap(dir);
}

VisibilityResult MappingWorker::visibilityResult() const {
  std::lock_guard<std::mutex> lock(backend_mutex_);
  return visibility_;
}

MapStats MappingWorker::stats() const {
  std::lock_guard<std::mutex> lock(backend_mutex_);
  MapStats s = backend_->stats();
  s.keyframes -= std::min(s.keyframes, supplements_);
  return s;
}

std::size_t MappingWorker::reintegratedKeyframes() const {
  std::lock_guard<std::mutex> lock(backend_mutex_);
  return reintegrated_;
}

}  // namespace dynamap
