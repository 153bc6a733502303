#include "frame_prefetch.hpp"

namespace dynamap {

FramePrefetcher::~FramePrefetcher() {
  if (pending_.valid()) pending_.wait();  // the reading thread uses sequence_: let it finish
}

FrameLoad FramePrefetcher::take(std::size_t index) {
  FrameLoad load;
  if (pending_.valid() && pending_index_ == index) {
    load = pending_.get();
  } else {
    if (pending_.valid()) pending_.wait();  // a frame skipped (--realtime): not needed
    pending_ = {};
    load = sequence_.load(index);
  }
  if (index + 1 < sequence_.size()) {
    pending_index_ = index + 1;
    pending_ = std::async(std::launch::async, [this, next = index + 1] {
      FrameLoad next_load = sequence_.load(next);
      if (next_load.ok && on_read_) on_read_(next_load.frame);
      return next_load;
    });
  }
  return load;
}

}  // namespace dynamap
