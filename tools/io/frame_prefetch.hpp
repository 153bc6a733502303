#pragma once

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include "tum_dataset.hpp"

namespace dynamap {

/// Reads the next frame of a sequence on another thread while the caller processes this one:
/// decoding a colour JPEG/PNG and a 16-bit depth PNG takes ~5 ms a frame, which would
/// otherwise sit on the tracking thread's path. take(i) returns frame i exactly as
/// TumSequence::load(i) would (same bytes, same errors) and starts reading i + 1. One reading
/// thread for the whole sequence (its decode buffers stay warm). take() is for one caller thread.
class FramePrefetcher {
 public:
  /// `on_read`, if given, receives each frame read ahead that loaded, on the reading thread.
  explicit FramePrefetcher(const TumSequence& sequence,
                           std::function<void(const RgbdFrame&)> on_read = {});
  ~FramePrefetcher();
  FramePrefetcher(const FramePrefetcher&) = delete;
  FramePrefetcher& operator=(const FramePrefetcher&) = delete;

  /// Frame `index` (waits for it if it is being read; reads it now if another one was).
  FrameLoad take(std::size_t index);

 private:
  void loop();

  const TumSequence& sequence_;
  std::function<void(const RgbdFrame&)> on_read_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::optional<std::size_t> wanted_;  ///< the frame the reading thread is to read next
  std::optional<FrameLoad> ready_;     ///< what it read, for ready_index_
  std::size_t ready_index_ = 0;
  std::exception_ptr failure_;  ///< what reading ready_index_ threw (on_read may throw)
  bool busy_ = false;           ///< a frame asked for and not yet in ready_
  bool stop_ = false;
  std::thread thread_;  // last: starts once the rest is built
};

}  // namespace dynamap
