#pragma once

#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/frame.hpp"
#include "dynamap/core/timing.hpp"
#include "dynamap/core/tracker_config.hpp"
#include "dynamap/core/tracking/local_map.hpp"

namespace dynamap {

/// Solves a BA window in place (poses of non-fixed keyframes and all points): reprojection +
/// depth residuals, Huber loss, Ceres Schur solver. Returns false when nothing was solved.
bool solveBundleAdjustment(const PinholeCamera& camera, const TrackerConfig& config,
                           BaWindow& window);

/// Local bundle adjustment on its own thread. requestRun() (after each new keyframe) never
/// blocks; the thread snapshots the window, solves without holding the map lock and writes the
/// result back under it. Corrected keyframe poses queue up for takeUpdates(). Thread-safe.
/// With TrackerConfig::ba_lockstep the solved window is held back instead, until the tracker
/// calls applyFinished() (before its next keyframe): it waits for the solve in flight and writes
/// the result then, so the frames that see it do not depend on thread timing.
class LocalBundleAdjuster {
 public:
  LocalBundleAdjuster(const PinholeCamera& camera, const TrackerConfig& config, LocalMap& map,
                      TimingRecorder* timings);
  ~LocalBundleAdjuster();  ///< stops and joins
  LocalBundleAdjuster(const LocalBundleAdjuster&) = delete;
  LocalBundleAdjuster& operator=(const LocalBundleAdjuster&) = delete;

  /// Told of every write to the map (the moved keyframes and the map generation the window was
  /// taken in), on the thread that writes: the BA thread, or the caller of applyFinished() and
  /// runOnce(). Set before start().
  using WriteListener = std::function<void(const std::vector<PoseUpdate>&, int generation)>;
  void setWriteListener(WriteListener listener) { listener_ = std::move(listener); }

  void start();
  void requestRun();
  void stop();  ///< finishes the running solve, joins; idempotent
  /// One synchronous solve in the caller's thread ("ba_final"), of the newest window_keyframes
  /// (0 = ba_window) with at most max_iterations (0 = ba_max_iterations).
  void runOnce(int window_keyframes = 0, int max_iterations = 0);
  /// Runs requested since the last one over every keyframe (ba_global_every_keyframes).
  int runsSinceGlobal() const;
  std::vector<PoseUpdate> takeUpdates();
  /// Poses moved by someone else (loop closure) join the queue of takeUpdates(), in order.
  void queueUpdates(const std::vector<PoseUpdate>& moved);
  /// ba_lockstep: waits for the requested/running solve and writes its result to the map.
  void applyFinished();

 private:
  void loop();
  /// The current window of the map: every keyframe if `global`, else the newest ba_window.
  BaWindow snapshot(bool global) const;
  /// The newest `keyframes` keyframes with the fixed ones the config asks for.
  BaWindow windowOf(int keyframes) const;
  bool solve(BaWindow& window);        ///< timed as "ba" or "ba_global"; false = nothing solved
  bool nextRunIsGlobal();              ///< counts the request (requestRun(), under mutex_)
  void write(const BaWindow& solved);  ///< into the map; moved poses queue for takeUpdates()

  PinholeCamera camera_;
  TrackerConfig config_;
  LocalMap& map_;
  TimingRecorder* timings_;
  WriteListener listener_;  ///< set before start(), then read only
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool pending_ = false;
  bool running_ = false;
  bool stop_ = false;
  int requests_ = 0;                ///< requestRun() calls
  int since_global_ = 0;            ///< of them since the last global run
  bool pending_global_ = false;     ///< not lockstep: the pending run takes every keyframe
  std::optional<BaWindow> job_;     ///< ba_lockstep: the window requestRun() took
  std::optional<BaWindow> solved_;  ///< ba_lockstep: a finished solve not yet written
  std::thread thread_;
  std::mutex updates_mutex_;
  std::vector<PoseUpdate> updates_;
};

}  // namespace dynamap
