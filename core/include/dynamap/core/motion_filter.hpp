#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/frame.hpp"

namespace dynamap {

/// Frame-to-frame feature matches (from LK optical flow) between the previous and the current
/// frame, in pixels. prev_px[i] <-> cur_px[i].
struct FeatureMatches {
  std::vector<cv::Point2f> prev_px;
  std::vector<cv::Point2f> cur_px;
  /// Per match (empty: unknown): an id that stays with the tracked point from frame to frame
  /// (landmark ids for landmark tracks, kProbeIdBit | n for motion probes).
  std::vector<std::uint64_t> ids;
};

constexpr std::uint64_t kProbeIdBit = std::uint64_t{1} << 63;

/// What the tracker hands to the dynamic-point stage, between matching and pose estimation.
struct MotionFilterInput {
  const RgbdFrame* frame = nullptr;  ///< current frame (colour, depth)
  const cv::Mat* prev_gray = nullptr;
  const cv::Mat* cur_gray = nullptr;
  const FeatureMatches* matches = nullptr;
  /// The camera motion since the previous frame as the tracker's map sees it (a pose estimated
  /// against landmarks that several keyframes observed, before any motion decision), so that
  /// the geometric check does not have to take the frame-to-frame majority for the camera.
  bool has_prior = false;
  Eigen::Isometry3d T_prev_cur = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();  ///< the prior pose (with has_prior)
  /// Per match (may be null): 1 = a landmark that several keyframes saw at one place and that
  /// fits the prior motion: static over time, not just in this frame.
  const std::vector<std::uint8_t>* proven_static = nullptr;
};

/// Result of the dynamic-point stage.
struct MotionFilterOutput {
  std::vector<std::uint8_t> match_is_dynamic;  ///< one flag per match (1 = dynamic)
  cv::Mat dynamic_mask;  ///< CV_8UC1, 255 = moving region; empty = nothing moving
  /// Per match (may be empty): dynamic only for lack of proof that it is still (an object of a
  /// moving class not yet confirmed static) and not flagged itself. The tracker may use these
  /// when the rest of the image cannot hold a pose.
  std::vector<std::uint8_t> match_held;
  cv::Mat unconfirmed_mask;  ///< CV_8UC1 (may be empty): the pixels behind match_held
  /// CV_8UC1 (may be empty): the part of dynamic_mask whose objects showed no motion of their own
  /// in this frame (masked only until they prove still), and the pixels of objects confirmed
  /// static over time. They reach KeyframePacket for mapping to judge in hindsight.
  cv::Mat held_mask;
  cv::Mat confirmed_mask;
  /// CV_8UC1 (may be empty): the part of dynamic_mask on moving objects that are not people
  /// (FusionResult::moved_objects), for mapping's votes.
  cv::Mat moved_object_mask;
};

/// Hook between feature matching and pose estimation. The tracker drops dynamic matches and
/// every feature inside `dynamic_mask` from pose estimation, bundle adjustment and new
/// landmarks, and attaches the mask to keyframe packets.
/// Called from the tracking thread only (prefetch() excepted); need not be thread-safe otherwise.
class MotionFilter {
 public:
  virtual ~MotionFilter() = default;
  /// Called at the start of Tracker::track(), before feature matching, so that slow work
  /// (e.g. the object detector) can run on its own thread while the tracker matches features.
  virtual void beginFrame(const RgbdFrame& frame) = 0;
  /// The frame that will be begun next, as soon as it is read (before the current frame is
  /// done), so that slow work on it may start early. Optional; may be called from another
  /// thread than the tracking one (implementations that use it must be thread-safe there).
  virtual void prefetch(const RgbdFrame& next) { (void)next; }
  /// Called between matching and pose estimation with the frame passed to beginFrame().
  virtual MotionFilterOutput filter(const MotionFilterInput& input) = 0;
};

}  // namespace dynamap
