#include "dynamap/core/timing.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace dynamap {

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const auto hi = std::min(lo + 1, values.size() - 1);
  const double frac = pos - static_cast<double>(lo);
  return values[lo] * (1.0 - frac) + values[hi] * frac;
}

void TimingRecorder::add(const std::string& stage, double duration_ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  samples_ms_[stage].push_back(duration_ms);
}

namespace {
StageStats summarize(const std::vector<double>& v) {
  StageStats s;
  s.count = v.size();
  if (v.empty()) return s;
  s.median_ms = percentile(v, 50.0);
  s.p95_ms = percentile(v, 95.0);
  s.mean_ms = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  s.max_ms = *std::max_element(v.begin(), v.end());
  return s;
}
}  // namespace

StageStats TimingRecorder::stats(const std::string& stage) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = samples_ms_.find(stage);
  return it == samples_ms_.end() ? StageStats{} : summarize(it->second);
}

std::map<std::string, StageStats> TimingRecorder::allStats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::map<std::string, StageStats> out;
  for (const auto& [name, v] : samples_ms_) out[name] = summarize(v);
  return out;
}

double ScopedStageTimer::stop() {
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start_).count();
  if (!stopped_ && recorder_ != nullptr) recorder_->add(stage_, ms);
  stopped_ = true;
  return ms;
}

}  // namespace dynamap
