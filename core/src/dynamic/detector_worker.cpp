#include "dynamap/core/dynamic/detector_worker.hpp"

#include <algorithm>
#include <chrono>
#include <utility>

namespace dynamap {

namespace {

/// OpenCV's pool size is set before the worker thread and any tracking start: set from the
/// worker itself, it changed under the tracker's first ORB/LK calls at a moment that depended
/// on thread timing, and a loaded machine then gave other keypoints (other trajectories).
void applyThreads(int threads) {
  if (threads > 0) cv::setNumThreads(threads);
}

}  // namespace

DetectorWorker::DetectorWorker(std::unique_ptr<ObjectDetector> detector, int threads,
                               std::function<void(double)> record_ms)
    : detector_(std::move(detector)),
      record_ms_(std::move(record_ms)),
      thread_((applyThreads(threads), [this] { loop(); })) {}

DetectorWorker::~DetectorWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

bool DetectorWorker::beganPending() const {
  return (busy_ && flight_frame_ != kReadAhead) ||
         std::any_of(jobs_.begin(), jobs_.end(),
                     [](const Job& j) { return j.frame_no != kReadAhead; });
}

bool DetectorWorker::readAheadPending() const {
  return (busy_ && flight_frame_ == kReadAhead && !flight_dropped_) ||
         std::any_of(jobs_.begin(), jobs_.end(),
                     [](const Job& j) { return j.frame_no == kReadAhead; }) ||
         std::any_of(done_.begin(), done_.end(),
                     [](const Done& d) { return d.result.frame_no == kReadAhead; });
}

// The frame read ahead becomes frame `frame_no` if it has this timestamp; any other frame read
// ahead was never begun and is dropped.
bool DetectorWorker::adoptReadAhead(long frame_no, double stamp) {
  bool adopted = false;
  for (auto it = jobs_.begin(); it != jobs_.end();) {
    if (it->frame_no != kReadAhead) {
      ++it;
    } else if (it->stamp == stamp && !adopted) {
      it->frame_no = frame_no, adopted = true, ++it;
    } else {
      it = jobs_.erase(it);
    }
  }
  if (busy_ && flight_frame_ == kReadAhead && !flight_dropped_) {
    if (flight_stamp_ == stamp && !adopted) {
      flight_frame_ = frame_no, adopted = true;
    } else {
      flight_dropped_ = true;
    }
  }
  for (auto it = done_.begin(); it != done_.end();) {
    if (it->result.frame_no != kReadAhead) {
      ++it;
    } else if (it->result.stamp == stamp && !adopted) {
      it->result.frame_no = frame_no, adopted = true, ++it;
    } else {
      it = done_.erase(it);
    }
  }
  return adopted;
}

bool DetectorWorker::submit(const cv::Mat& bgr, long frame_no, double stamp, bool wait) {
  std::unique_lock<std::mutex> lock(mutex_);
  begun_any_ = true;
  last_begun_stamp_ = stamp;
  if (adoptReadAhead(frame_no, stamp)) return true;
  if (wait) cv_.wait(lock, [&] { return jobs_.empty() && !busy_; });
  if (!jobs_.empty() || busy_) return false;
  jobs_.push_back({bgr.clone(), frame_no, stamp});
  cv_.notify_all();
  return true;
}

void DetectorWorker::prefetch(const cv::Mat& bgr, double stamp) {
  std::lock_guard<std::mutex> lock(mutex_);
  // A frame already begun (its read-ahead came late) is not detected twice.
  if (readAheadPending() || stop_ || (begun_any_ && stamp <= last_begun_stamp_)) return;
  jobs_.push_back({bgr.clone(), kReadAhead, stamp});
  cv_.notify_all();
}

bool DetectorWorker::take(Result* out, bool wait) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (wait) cv_.wait(lock, [&] { return !beganPending(); });
  // The newest result of a begun frame; older ones are superseded, read-ahead ones stay.
  auto newest = done_.end();
  for (auto it = done_.begin(); it != done_.end(); ++it) {
    if (it->result.frame_no != kReadAhead) newest = it;
  }
  if (newest == done_.end()) return false;
  Done taken = std::move(*newest);
  done_.erase(std::remove_if(done_.begin(), done_.end(),
                             [](const Done& d) { return d.result.frame_no != kReadAhead; }),
              done_.end());
  if (taken.error) std::rethrow_exception(taken.error);
  *out = std::move(taken.result);
  return true;
}

std::vector<Detection> DetectorWorker::runNow(const cv::Mat& bgr) {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [&] { return jobs_.empty() && !busy_; });
  done_.clear();
  const auto start = std::chrono::steady_clock::now();
  auto dets = detector_->detect(bgr);
  record_ms_(
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  return dets;
}

void DetectorWorker::loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    cv_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
    if (stop_) return;
    Job job = std::move(jobs_.front());
    jobs_.pop_front();
    busy_ = true;
    flight_frame_ = job.frame_no;
    flight_stamp_ = job.stamp;
    flight_dropped_ = false;
    lock.unlock();
    Done done;
    const auto start = std::chrono::steady_clock::now();
    try {
      done.result.detections = detector_->detect(job.bgr);
    } catch (...) {
      done.error = std::current_exception();
    }
    record_ms_(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                   .count());
    lock.lock();
    done.result.frame_no = flight_frame_;  // given meanwhile if the frame was read ahead
    done.result.stamp = job.stamp;
    if (!flight_dropped_) done_.push_back(std::move(done));
    busy_ = false;
    flight_frame_ = kReadAhead;
    cv_.notify_all();
  }
}

}  // namespace dynamap
