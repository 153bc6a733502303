#pragma once

#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace dynamap {

/// Summary of one stage's durations.
struct StageStats {
  std::size_t count = 0;
  double median_ms = 0.0;
  double p95_ms = 0.0;
  double mean_ms = 0.0;
  double max_ms = 0.0;
};

/// Collects per-stage durations from any thread. Thread-safe.
class TimingRecorder {
 public:
  void add(const std::string& stage, double duration_ms);
  StageStats stats(const std::string& stage) const;
  std::map<std::string, StageStats> allStats() const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, std::vector<double>> samples_ms_;
};

/// RAII timer: records the time from construction to destruction (or stop()) under `stage`.
class ScopedStageTimer {
 public:
  ScopedStageTimer(TimingRecorder* recorder, std::string stage)
      : recorder_(recorder), stage_(std::move(stage)), start_(Clock::now()) {}
  ~ScopedStageTimer() { stop(); }
  ScopedStageTimer(const ScopedStageTimer&) = delete;
  ScopedStageTimer& operator=(const ScopedStageTimer&) = delete;

  /// Records once; returns the elapsed milliseconds.
  double stop();

 private:
  using Clock = std::chrono::steady_clock;
  TimingRecorder* recorder_;
  std::string stage_;
  Clock::time_point start_;
  bool stopped_ = false;
};

/// Median / percentile helpers (values need not be sorted; p in [0, 100], linear interpolation).
double percentile(std::vector<double> values, double p);

}  // namespace dynamap
