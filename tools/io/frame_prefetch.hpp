#pragma once

#include <cstddef>
#include <functional>
#include <future>
#include <utility>

#include "tum_dataset.hpp"

namespace dynamap {

/// Reads the next frame of a sequence on another thread while the caller processes this one:
/// decoding a colour JPEG/PNG and a 16-bit depth PNG takes ~5 ms a frame, which would
/// otherwise sit on the tracking thread's path. take(i) returns frame i exactly as
/// TumSequence::load(i) would (same bytes, same errors) and starts reading i + 1.
class FramePrefetcher {
 public:
  /// `on_read`, if given, receives each frame read ahead that loaded, on the reading thread.
  explicit FramePrefetcher(const TumSequence& sequence,
                           std::function<void(const RgbdFrame&)> on_read = {})
      : sequence_(sequence), on_read_(std::move(on_read)) {}
  ~FramePrefetcher();
  FramePrefetcher(const FramePrefetcher&) = delete;
  FramePrefetcher& operator=(const FramePrefetcher&) = delete;

  /// Frame `index` (waits for it if it is being read; reads it now if another one was).
  FrameLoad take(std::size_t index);

 private:
  const TumSequence& sequence_;
  std::function<void(const RgbdFrame&)> on_read_;
  std::future<FrameLoad> pending_;
  std::size_t pending_index_ = 0;
};

}  // namespace dynamap
