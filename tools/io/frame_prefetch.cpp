#include "frame_prefetch.hpp"

#include <exception>

namespace dynamap {

FramePrefetcher::FramePrefetcher(const TumSequence& sequence,
                                 std::function<void(const RgbdFrame&)> on_read)
    : sequence_(sequence), on_read_(std::move(on_read)), thread_([this] { loop(); }) {}

FramePrefetcher::~FramePrefetcher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;  // a frame being read is finished first: the thread uses sequence_
  }
  changed_.notify_all();
  thread_.join();
}

void FramePrefetcher::loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    changed_.wait(lock, [this] { return stop_ || wanted_.has_value(); });
    if (stop_) return;
    const std::size_t index = *wanted_;
    wanted_.reset();
    lock.unlock();
    FrameLoad load;
    std::exception_ptr failure;
    try {
      load = sequence_.load(index);
      if (load.ok && on_read_) on_read_(load.frame);
    } catch (...) {
      failure = std::current_exception();  // thrown again by take(), on the caller's thread
    }
    lock.lock();
    ready_ = std::move(load);
    failure_ = failure;
    ready_index_ = index;
    busy_ = false;
    changed_.notify_all();
  }
}

FrameLoad FramePrefetcher::take(std::size_t index) {
  std::optional<FrameLoad> load;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [this] { return !busy_; });  // a frame skipped (--realtime): not needed
    if (ready_ && ready_index_ == index) {
      if (failure_) std::rethrow_exception(std::exchange(failure_, nullptr));
      load = std::move(ready_);
    }
    ready_.reset();
    failure_ = nullptr;
  }
  if (!load) load = sequence_.load(index);
  if (index + 1 < sequence_.size()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      wanted_ = index + 1;
      busy_ = true;
    }
    changed_.notify_all();
  }
  return std::move(*load);
}

}  // namespace dynamap
