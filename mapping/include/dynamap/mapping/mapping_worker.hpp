#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "dynamap/core/frame.hpp"
#include "dynamap/core/timing.hpp"
#include "dynamap/mapping/held_revision.hpp"
#include "dynamap/mapping/map_backend.hpp"
#include "dynamap/mapping/static_points.hpp"

namespace dynamap {

/// Runs a backend on its own thread behind a bounded queue of keyframe packets. Pose updates
/// from bundle adjustment are forwarded to the backend; volumetric backends (kReintegrate) are
/// rebuilt with the final poses in finish() when some keyframe moved by more than
/// `kReintegrateTranslationM` / `kReintegrateRotationRad`. For that the worker keeps each
/// keyframe's static depth (16-bit, 0.2 mm) and colour. With options.free_space enabled, a
/// keyframe is integrated once its `neighbours` later keyframes have arrived (or at finish()),
/// without the pixels that lie in free space seen by up to `neighbours` keyframes on each side
/// (freeSpaceViolations(): movers the masks missed). With options.visibility enabled, finish()
/// checks every map element against every keyframe with the final poses (removeSeenThrough():
/// what any keyframe saw through is removed) and rebuilds the map without it, whatever the
/// backend; for that it keeps every keyframe's static depth, colour and a 1/downsample
/// resolution view of its depth (VisibilityView); and with options.deferred_integration (the
/// default) the backend sees the keyframes only then, after the pass, with the final poses: the
/// mapping thread keeps their static depth and views while the camera runs. All public methods are
/// thread-safe; exportMap() and stats() after finish() see the final map.
class MappingWorker {
 public:
  static constexpr double kReintegrateTranslationM = 0.01;
  static constexpr double kReintegrateRotationRad = 0.5 * 3.14159265358979 / 180.0;

  MappingWorker(std::unique_ptr<MapBackend> backend, const PinholeCamera& camera,
                const StaticPointsOptions& options, std::size_t queue_capacity,
                TimingRecorder* timings, int thread_nice = 0);
  ~MappingWorker();
  MappingWorker(const MappingWorker&) = delete;
  MappingWorker& operator=(const MappingWorker&) = delete;

  /// Blocks while the queue is full.
  void push(KeyframePacketPtr kf);
  /// Non-blocking; returns false (and counts a drop) when the queue is full.
  bool tryPush(KeyframePacketPtr kf);
  void applyPoseUpdates(const std::vector<PoseUpdate>& updates);
  /// Stops taking keyframes, integrates the queued ones and stops the thread, then prepares what
  /// finish() needs that no pose changes (the held depths as metres). Meant to run beside the
  /// tracker's last bundle adjustment; applyPoseUpdates() may be called during and after it.
  /// finish() does it if it was not called. Idempotent.
  void drain();
  /// Drains the queue, stops the thread, applies the final poses (rebuild if needed). Idempotent.
  void finish();
  void exportMap(const std::string& dir);
  MapStats stats() const;
  std::size_t droppedKeyframes() const { return dropped_.load(); }
  /// Keyframes re-integrated by the final rebuild (0 if none was needed).
  std::size_t reintegratedKeyframes() const;
  /// The visibility pass of finish() (all zero before finish() or when it is disabled).
  VisibilityResult visibilityResult() const;
  /// After finish(): the masks that the held-back revision changed (keyframe id -> the mask the
  /// map used), see StaticPointsOptions::held_revision_voxel_m.
  std::unordered_map<std::uint64_t, cv::Mat> revisedMasks() const;

 private:
  struct KeyframeRecord {
    double timestamp_s = 0.0;
    Eigen::Isometry3d T_integrated = Eigen::Isometry3d::Identity();
    Eigen::Isometry3d T_current = Eigen::Isometry3d::Identity();
    cv::Mat depth_u16;  ///< static depth, 1/5000 m
    cv::Mat bgr;
    VisibilityView view;  ///< options.visibility enabled only
    /// options.held_revision_voxel_m > 0 and held pixels only, until finish(): the held and
    /// confirmed pixels, the raw depth, the keyframe's mask and the free-space check's
    HeldKeyframe held;
    cv::Mat held_depth_u16;
    cv::Mat dynamic_mask;
    cv::Mat extra_mask;
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
  void integratePacket(const KeyframePacket& kf, const cv::Mat& extra_mask);
  /// Rebuilds when a volumetric backend's keyframe moved, or always when `force`.
  void rebuildIfNeeded(bool force);
  /// The visibility pass over all keyframes; true if it removed pixels.
  bool removeSeenThroughLocked();
  /// Unmasks held-back pixels that another keyframe confirmed static; true if any.
  bool reviseHeldLocked();
  void prepareHeldLocked();
  void applyUpdateLocked(const PoseUpdate& update);
  /// Keyframes go to the backend only in finish() (see the class comment).
  bool deferred() const { return options_.visibility.enabled && options_.deferred_integration; }

  std::unique_ptr<MapBackend> backend_;
  PinholeCamera camera_;
  StaticPointsOptions options_;
  std::size_t capacity_;
  int thread_nice_;  ///< the mapping thread's nice value (Linux), 0 = the process's
  TimingRecorder* timings_;

  mutable std::mutex mutex_;  ///< guards queue_, pending_updates_, stopping_
  std::condition_variable not_empty_;
  std::condition_variable not_full_;
  std::deque<KeyframePacketPtr> queue_;
  std::vector<PoseUpdate> pending_updates_;
  bool stopping_ = false;
  bool finished_ = false;
  bool drained_ = false;   ///< guarded by backend_mutex_
  std::mutex join_mutex_;  ///< drain() may run on a helper thread: one join of thread_
  std::atomic<std::size_t> dropped_{0};

  mutable std::mutex backend_mutex_;  ///< guards backend_ and records_
  std::unordered_map<std::uint64_t, KeyframeRecord> records_;
  std::deque<WindowEntry> window_;  ///< mapping thread (then finish()) only
  std::vector<std::uint64_t> order_;
  std::unordered_map<std::uint64_t, Eigen::Isometry3d> early_updates_;
  std::size_t reintegrated_ = 0;
  VisibilityResult visibility_;
  std::unordered_map<std::uint64_t, cv::Mat> revised_masks_;
  std::thread thread_;
};

}  // namespace dynamap
