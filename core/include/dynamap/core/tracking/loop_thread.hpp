#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <thread>
#include <vector>

#include "dynamap/core/tracking/loop_closer.hpp"

namespace dynamap {

struct LoopThreadStats {
  std::size_t keyframes = 0;  ///< keyframes the loop thread took in
  std::size_t loops = 0;      ///< verified loops (detect() results; several per run of it count once)
  std::size_t closures = 0;   ///< pose-graph corrections handed to the tracker
};

/// The loop closer on its own thread, owned by the tracker (as LocalBundleAdjuster).
///
/// Threads: addKeyframe(), waitIdle(), takeCorrections() and stop() are called by the tracking
/// thread; updatePose() by any thread (the BA's). Keyframes and pose updates queue here and
/// reach the LoopCloser only when the loop thread wakes for a keyframe, all at once: with the
/// tracker waiting for it (waitIdle()) before each keyframe, what each detect() sees depends on
/// the frames alone, not on thread timing. Per wake: LoopCloser::addKeyframe/updatePose, then
/// detect(), then close() if a loop was found; corrections queue for takeCorrections(), oldest
/// first (each one's "before" poses are the previous one's "after").
class LoopClosureThread {
 public:
  LoopClosureThread(const PinholeCamera& camera, const TrackerConfig& tracker_config,
                    const LoopCloserConfig& config, TimingRecorder* timings);
  ~LoopClosureThread();  ///< stops and joins
  LoopClosureThread(const LoopClosureThread&) = delete;
  LoopClosureThread& operator=(const LoopClosureThread&) = delete;

  void start();
  void addKeyframe(LoopKeyframeInput keyframe);
  void updatePose(std::uint64_t id, const Eigen::Isometry3d& T_W_C, int generation);
  /// Waits until every keyframe added so far went through detect()/close(), then takes the
  /// corrections found.
  std::vector<LoopCorrection> waitIdle();
  std::vector<LoopCorrection> takeCorrections();  ///< does not wait
  void stop();  ///< finishes the running pass, joins; idempotent
  LoopThreadStats stats() const;

 private:
  struct PoseInput {
    std::uint64_t id;
    Eigen::Isometry3d T_W_C;
    int generation;
  };
  void loop();
  void pass(std::deque<LoopKeyframeInput>& keyframes, std::vector<PoseInput>& poses);

  LoopCloser closer_;  ///< loop thread only once started
  mutable std::mutex mutex_;  ///< guards the members below
  std::condition_variable wake_;
  std::deque<LoopKeyframeInput> keyframes_;
  std::vector<PoseInput> poses_;
  std::vector<LoopCorrection> corrections_;
  bool running_ = false;
  bool stop_ = false;
  LoopThreadStats stats_;
  std::thread thread_;
};

}  // namespace dynamap
