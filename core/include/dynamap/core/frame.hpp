#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace dynamap {

/// One associated colour + depth pair, already undistorted.
struct RgbdFrame {
  std::size_t index = 0;     ///< position in the sequence (0-based)
  double timestamp_s = 0.0;  ///< colour timestamp
  cv::Mat bgr;               ///< CV_8UC3
  cv::Mat depth_m;           ///< CV_32FC1, metres, 0 = no reading
};

/// Per-frame outcome of tracking. Expected outcomes are values, never exceptions.
enum class FrameStatus : std::uint8_t {
  kTracked,      ///< pose estimated from tracked features
  kRelocalized,  ///< pose recovered by relocalization after a loss
  kLost,         ///< no pose could be estimated; the pose is the last known one
  kPosedByDepth, ///< posed by the static depth alone (tracking.depth_fallback): no features held it
  kBadFrame,     ///< frame could not be read/decoded; skipped
};

const char* toString(FrameStatus status);

/// An immutable keyframe handed from tracking to mapping. Shared as
/// std::shared_ptr<const KeyframePacket> across threads.
struct KeyframePacket {
  std::uint64_t id = 0;
  double timestamp_s = 0.0;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();  ///< camera -> world
  cv::Mat bgr;                                              ///< CV_8UC3
  cv::Mat depth_m;                                          ///< CV_32FC1, 0 = no reading
  cv::Mat dynamic_mask;  ///< CV_8UC1, 255 = moving; empty = nothing dynamic
  /// CV_8UC1, may be empty (MotionFilterOutput): the part of dynamic_mask held back only for
  /// lack of evidence that it stands still, and the pixels of objects confirmed static. Mapping
  /// unmasks held pixels where another keyframe confirmed an object static.
  cv::Mat held_mask;
  cv::Mat confirmed_mask;
  /// CV_8UC1, may be empty (MotionFilterOutput::moved_object_mask): the part of dynamic_mask on
  /// moving objects that are not people.
  cv::Mat moved_object_mask;
};
using KeyframePacketPtr = std::shared_ptr<const KeyframePacket>;

/// A corrected keyframe pose published by bundle adjustment (or loop closure).
struct PoseUpdate {
  std::uint64_t keyframe_id = 0;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
};

}  // namespace dynamap
