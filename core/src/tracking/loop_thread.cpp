#include "dynamap/core/tracking/loop_thread.hpp"

namespace dynamap {

LoopClosureThread::LoopClosureThread(const PinholeCamera& camera,
                                     const TrackerConfig& tracker_config,
                                     const LoopCloserConfig& config, TimingRecorder* timings)
    : closer_(camera, tracker_config, config, timings) {}

LoopClosureThread::~LoopClosureThread() { stop(); }

void LoopClosureThread::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (thread_.joinable() || stop_) return;
  thread_ = std::thread([this] { loop(); });
}

void LoopClosureThread::addKeyframe(LoopKeyframeInput keyframe) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    keyframes_.push_back(std::move(keyframe));
  }
  wake_.notify_all();
}

void LoopClosureThread::updatePose(std::uint64_t id, const Eigen::Isometry3d& T_W_C,
                                   int generation) {
  std::lock_guard<std::mutex> lock(mutex_);
  poses_.push_back({id, T_W_C, generation});
}

std::vector<LoopCorrection> LoopClosureThread::waitIdle() {
  std::unique_lock<std::mutex> lock(mutex_);
  wake_.wait(lock, [this] {
    return (keyframes_.empty() && !running_) || !thread_.joinable() || stop_;
  });
  std::vector<LoopCorrection> out;
  out.swap(corrections_);
  return out;
}

std::vector<LoopCorrection> LoopClosureThread::takeCorrections() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<LoopCorrection> out;
  out.swap(corrections_);
  return out;
}

void LoopClosureThread::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

LoopThreadStats LoopClosureThread::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void LoopClosureThread::loop() {
  std::deque<LoopKeyframeInput> keyframes;
  std::vector<PoseInput> poses;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return !keyframes_.empty() || stop_; });
      if (stop_) return;
      keyframes.swap(keyframes_);
      poses.swap(poses_);
      running_ = true;
    }
    pass(keyframes, poses);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      running_ = false;
    }
    wake_.notify_all();
  }
}

// The LoopCloser takes the keyframes in before the pose updates (LoopCloser::detect()), so an
// update of a keyframe queued in the same pass is not lost.
void LoopClosureThread::pass(std::deque<LoopKeyframeInput>& keyframes,
                             std::vector<PoseInput>& poses) {
  for (const PoseInput& p : poses) closer_.updatePose(p.id, p.T_W_C, p.generation);
  const std::size_t added = keyframes.size();
  for (auto& k : keyframes) closer_.addKeyframe(std::move(k));
  keyframes.clear();
  poses.clear();
  const bool found = closer_.detect().has_value();
  std::optional<LoopCorrection> correction;
  if (found) correction = closer_.close();
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.keyframes += added;
  stats_.loops = closer_.loops().size();
  if (correction) {
    ++stats_.closures;
    corrections_.push_back(std::move(*correction));
  }
}

}  // namespace dynamap
