#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

#include "dynamap/core/frame.hpp"
#include "dynamap/core/timing.hpp"
#include "dynamap/mapping/held_revision.hpp"
#include "dynamap/mapping/map_backend.hpp"
#include "dynamap/mapping/static_points.hpp"

namespace dynamap {

/// Runs a backend on its own thread behind a bounded queue of keyframe packets. With
/// options.free_space enabled, a keyframe first waits for its `neighbours` later keyframes and
/// loses the pixels that lie in free space seen by up to `neighbours` keyframes on each side
/// (freeSpaceViolations(): movers the masks missed). Then, online (the default), it waits in the
/// judgement window until a keyframe options.window_after_s later has arrived: its held-back
/// pixels are revised (heldConfirmedElsewhere()) and what the keyframes within window_before_s
/// before and window_after_s after it saw through or voted out is removed (removeSeenThrough()),
/// all with the current poses, and it goes to the backend. Pose updates go to the backend as they
/// come (kInPlace); volumetric backends (kReintegrate) follow them in finish() where a keyframe
/// moved by more than `kReintegrateTranslationM` / `kReintegrateRotationRad` (or, if larger,
/// half a cell of the backend's map, MapBackend::cellSizeM(), the rotation in proportion): a
/// backend that can take keyframes out has those moved out and in again, else the map is
/// rebuilt (for that the worker keeps their keyframes' static depth, 16-bit, and colour; a
/// kInPlace backend's are released once integrated, the views once out of the window). With
/// options.visibility_final_pass (the offline extra) the keyframes go to the backend only in
/// finish(), after the held revision and the visibility pass over all of them with the final
/// poses. All public methods are thread-safe; exportMap() and stats() see the map as it is
/// (final after finish()).
class MappingWorker {
 public:
  static constexpr double kReintegrateTranslationM = 0.01;
  static constexpr double kReintegrateRotationRad = 0.5 * 3.14159265358979 / 180.0;
  static constexpr std::uint64_t kSupplementBit = std::uint64_t{1} << 63;
  static constexpr std::size_t kAfterFinalPosesQueue = 4;

  MappingWorker(std::unique_ptr<MapBackend> backend, const PinholeCamera& camera,
                const StaticPointsOptions& options, std::size_t queue_capacity,
                TimingRecorder* timings, int thread_nice = 0);
  ~MappingWorker();
  MappingWorker(const MappingWorker&) = delete;
  MappingWorker& operator=(const MappingWorker&) = delete;

  /// The map a backend of this kind exported into `dir` as the backend's first content
  /// (MapBackend::importMap(): pose updates never move it, a rebuild keeps it, new keyframes add
  /// to it). Returns false if the backend cannot take a saved map; throws MappingError naming the
  /// file and the field for a missing, corrupt or mismatched one. Call before the first push().
  bool importMap(const std::string& dir);
  /// Blocks while the queue is full (for a backend that drainsAfterFinalPoses(), at
  /// kAfterFinalPosesQueue keyframes).
  void push(KeyframePacketPtr kf);
  /// Non-blocking; returns false (and counts a drop) when the queue is full.
  bool tryPush(KeyframePacketPtr kf);
  void applyPoseUpdates(const std::vector<PoseUpdate>& updates);
  /// Stops taking keyframes, integrates the queued ones and stops the thread, then prepares what
  /// finish() needs that no pose changes (the held depths as metres). Meant to run beside the
  /// tracker's last bundle adjustment; applyPoseUpdates() may be called during and after it.
  /// finish() does it if it was not called. Idempotent.
  void drain();
  /// true: the backend follows moved keyframes by integrating them again (kReintegrate, online),
  /// so the last keyframes are best drained after the final poses came (they then go in once,
  /// at those poses); false: beside the last bundle adjustment.
  bool drainsAfterFinalPoses() const {
    return !deferred() && backend_->poseUpdateMode() == PoseUpdateMode::kReintegrate;
  }
  /// Drains the queue, stops the thread, applies the final poses (rebuild if needed). Idempotent.
  void finish();
  /// Blocks until the keyframes queued so far have been taken and processed (those still in a
  /// window wait there): a snapshot then holds every keyframe old enough.
  void waitIdle();
  void exportMap(const std::string& dir);
  MapStats stats() const;
  std::size_t droppedKeyframes() const { return dropped_.load(); }
  /// Keyframes re-integrated to follow their final poses: every one by a rebuild, or those
  /// moved out and in again (0 if none was needed).
  std::size_t reintegratedKeyframes() const;
  /// The visibility votes so far (online: summed over the windows; final pass: after finish()).
  VisibilityResult visibilityResult() const;
  /// After finish(): the masks that the held-back revision changed (keyframe id -> the mask the
  /// map used), see StaticPointsOptions::held_revision_voxel_m.
  std::unordered_map<std::uint64_t, cv::Mat> revisedMasks() const;

 private:
  static constexpr double kDepthUnitsPerM = 5000.0;  ///< KeyframeRecord's 16-bit depths: 1/5000 m
  struct KeyframeRecord {
    double timestamp_s = 0.0;
    Eigen::Isometry3d T_integrated = Eigen::Isometry3d::Identity();
    Eigen::Isometry3d T_current = Eigen::Isometry3d::Identity();
    cv::Mat depth_u16;  ///< static depth, 1 / kDepthUnitsPerM m
    cv::Mat bgr;
    VisibilityView view;  ///< options.visibility enabled only
    /// options.held_revision_voxel_m > 0 and held pixels only, until finish(): the held and
    /// confirmed pixels, the raw depth, the keyframe's mask and the free-space check's
    HeldKeyframe held;
    cv::Mat held_depth_u16;
    cv::Mat dynamic_mask;
    cv::Mat extra_mask;
    bool integrated = false;  ///< the backend has it
    /// Online: integrated with held pixels kept for a second look once the keyframes
    /// options.held_window_after_s later are there (the pixels unmasked then go to the backend
    /// as keyframe id | kSupplementBit); `held_hits` are the first look's.
    bool rejudge_held = false;
    bool supplemented = false;
    cv::Mat held_hits;
    /// Online, one of the run's first options.startup_s of keyframes: judged in its window, it
    /// waits for a second visibility judgement once the keyframes
    /// options.startup_window_after_s later are there, and is integrated then.
    bool startup_wait = false;
  };
  struct WindowEntry {
    KeyframePacketPtr kf;
    FreeSpaceView view;
    bool integrated = false;
  };
  void run();
  /// Adds a keyframe to the free-space window and integrates those whose neighbours are there
  /// (all of them when `flush`).
  void advanceWindow(KeyframePacketPtr kf, bool flush);
  /// Makes the keyframe's record; online, puts it into the judgement window.
  void integratePacket(const KeyframePacket& kf, const cv::Mat& extra_mask);
  /// Online: judges the keyframes of the window whose later keyframes are there (all when
  /// `flush`) and integrates them (mapping_window.cpp).
  void judgeReadyLocked(bool flush);
  /// The held revision's first look for the window's keyframes [begin, end) and the second look
  /// for the judged ones due (all when `flush`), on one set of votes.
  void reviseHeldWindowLocked(std::size_t begin, std::size_t end, bool flush);
  void removeSeenThroughWindowLocked(std::size_t begin, std::size_t end);
  /// Visibility votes of `ids` (views; earlier visits' first) on the keyframes ids[begin, end).
  void removeSeenThroughLocked(const std::vector<std::uint64_t>& ids, std::size_t begin,
                               std::size_t end, const VisibilityOptions& options);
  /// True if `rec`, judged in its window, is one of the run's first startup_s of keyframes that
  /// wait for their second judgement (KeyframeRecord::startup_wait).
  bool waitsForStartupLook(const KeyframeRecord& rec) const;
  /// The startup keyframes' second judgement against the window as it is now, for those whose
  /// keyframes startup_window_after_s later are there (all when `flush`); integrates them.
  void judgeStartupLocked(bool flush);
  void integrateRecordLocked(std::uint64_t id);
  /// Unmasks keyframe `id`'s pixels `hit` (held back, confirmed static elsewhere) and remakes its
  /// static depth from `depth_m` (its raw depth); releases its held-revision data unless
  /// `keep_held`. Returns the revised mask (empty if none). Touches only that record.
  cv::Mat reviseOneLocked(std::uint64_t id, const cv::Mat& hit, const cv::Mat& depth_m,
                          bool keep_held);
  /// The held pixels' second look (see KeyframeRecord::rejudge_held): integrates what `hit`
  /// unmasks beyond the first look as the keyframe's supplement; releases its held data.
  void secondLookLocked(std::uint64_t id, const cv::Mat& hit, const cv::Mat& depth_m);
  /// heldConfirmedElsewhere() over the window for the window's keyframes with `looked` set
  /// (their raw depth as metres in `depth_m`, one per window entry; empty for the others).
  std::vector<cv::Mat> heldHitsLocked(const std::vector<char>& looked,
                                      std::vector<cv::Mat>& depth_m);
  void addVisibilityTimings(const VisibilityResult& r);
  /// Online: whether a keyframe leaving the window keeps its view for later visits.
  bool keepForRevisitsLocked(const KeyframeRecord& rec) const;
  /// The kept views of earlier visits near `T_W_C` (options.window_revisit_keyframes), in time
  /// order.
  std::vector<std::uint64_t> revisitContextLocked(const Eigen::Isometry3d& T_W_C) const;
  /// Brings a volumetric backend's keyframes that moved to their current poses: each taken out
  /// and in again while fewer than half moved and the backend can (MapBackend::deintegrate()),
  /// else the whole map rebuilt; the whole map always when `force`.
  void rebuildIfNeeded(bool force);
  /// Takes each keyframe out at the pose it went in with and integrates it at its current one.
  void moveKeyframesLocked(const std::vector<std::uint64_t>& ids);
  /// The static depth (metres) and, if the backend needs them, points of keyframe `id`'s record.
  void recordPointsLocked(std::uint64_t id, StaticPoints& sp) const;
  /// The visibility pass over all keyframes; true if it removed pixels.
  bool removeSeenThroughLocked();
  /// Unmasks held-back pixels that another keyframe confirmed static; true if any.
  bool reviseHeldLocked();
  void prepareHeldLocked();
  void applyUpdateLocked(const PoseUpdate& update);
  /// Keyframes go to the backend only in finish() (see the class comment).
  bool deferred() const { return options_.visibility_final_pass; }
  /// The backend needs the stored keyframes again for a rebuild.
  /// What push() lets queue up: capacity_, at most kAfterFinalPosesQueue for a backend that
  /// drains after the final poses (what is queued at finish() goes in after the final bundle
  /// adjustment, not beside it: the queue bounds the finish; octomap x1 with 16: 1.1-1.5 s).
  std::size_t pushLimit() const {
    return drainsAfterFinalPoses() ? std::min(capacity_, kAfterFinalPosesQueue) : capacity_;
  }
  bool keepsDepth() const {
    return deferred() || backend_->poseUpdateMode() == PoseUpdateMode::kReintegrate;
  }

  std::unique_ptr<MapBackend> backend_;
  PinholeCamera camera_;
  StaticPointsOptions options_;
  std::size_t capacity_;
  int thread_nice_;  ///< the mapping thread's nice value (Linux), 0 = the process's
  TimingRecorder* timings_;

  mutable std::mutex
      mutex_;  ///< guards queue_, pending_updates_, pushed_, taken_, stopping_, busy_
  std::condition_variable not_empty_;
  std::condition_variable not_full_;
  std::condition_variable idle_;
  bool busy_ = false;  ///< the thread is processing what it took from the queue
  std::deque<KeyframePacketPtr> queue_;
  /// Pose updates with the number of keyframes queued before them: the thread applies each after
  /// those keyframes and before the next, so the map does not depend on thread timing.
  std::deque<std::pair<std::size_t, PoseUpdate>> pending_updates_;
  std::size_t pushed_ = 0;  ///< keyframes queued so far
  std::size_t taken_ = 0;   ///< keyframes the thread took so far
  bool stopping_ = false;
  bool finished_ = false;
  bool drained_ = false;   ///< guarded by backend_mutex_
  std::mutex join_mutex_;  ///< drain() may run on a helper thread: one join of thread_
  std::atomic<std::size_t> dropped_{0};

  mutable std::mutex backend_mutex_;  ///< guards backend_ and records_
  std::unordered_map<std::uint64_t, KeyframeRecord> records_;
  std::deque<WindowEntry> window_;    ///< mapping thread (then finish()) only
  std::vector<std::uint64_t> order_;  ///< every keyframe recorded, in order
  /// Online: the judgement window in time order; [0, judged_) are judged context.
  std::deque<std::uint64_t> judge_;
  std::size_t judged_ = 0;
  double first_keyframe_s_ = -1.0;  ///< online: the first keyframe's time (-1: none yet)
  std::vector<std::uint64_t> startup_waiting_;  ///< online: KeyframeRecord::startup_wait ones
  std::vector<std::uint64_t> revisit_;  ///< online: keyframes whose view is kept for revisits
  std::unordered_map<std::uint64_t, Eigen::Isometry3d> early_updates_;
  std::size_t reintegrated_ = 0;
  /// Held second looks in the backend (not counted as keyframes).
  std::size_t supplements_ = 0;
  VisibilityResult visibility_;
  std::unordered_map<std::uint64_t, cv::Mat> revised_masks_;
  std::thread thread_;
};

}  // namespace dynamap
