#include "dynamap/core/frame.hpp"

namespace dynamap {

const char* toString(FrameStatus status) {
  switch (status) {
    case FrameStatus::kTracked:
      return "tracked";
    case FrameStatus::kRelocalized:
      return "relocalized";
    case FrameStatus::kLost:
      return "lost";
    case FrameStatus::kPosedByDepth:
      return "depth";
    case FrameStatus::kBadFrame:
      return "bad_frame";
  }
  return "unknown";
}

}  // namespace dynamap
