#pragma once

#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/timing.hpp"
#include "dynamap/core/tracker_config.hpp"
#include "dynamap/core/tracking/loop_verifier.hpp"
#include "dynamap/core/tracking/place_recognition.hpp"
#include "dynamap/core/tracking/pose_graph.hpp"

namespace dynamap {

struct LoopCloserConfig {
  PlaceRecognitionParams place;
  LoopVerifierParams verify;
  int exclude_newest = 20;      ///< temporal neighbours never proposed as a loop
  int min_shared_landmarks = 10;  ///< keyframes sharing this many landmark ids are covisible
  int max_candidates = 3;       ///< best-voted candidates verified per query
  double min_vote_share = 0.1;  ///< candidate votes / query descriptors, below: not verified
  int neighbour_span = 2;       ///< candidate's neighbours checked: up to this many each side
  double odometry_sigma_m = 0.01, odometry_sigma_deg = 0.5;  ///< per odometry edge
  double loop_sigma_m = 0.02, loop_sigma_deg = 1.0;          ///< per loop edge
  /// Cauchy loss on loop edges (second pass). Off by default: drift larger than the odometry
  /// sigmas explain makes a lone true loop edge look like an outlier, and verification already
  /// rejects false loops.
  bool robust_loop_edges = false;
  PoseGraphOptions graph;
};

/// One keyframe as handed to LoopCloser::addKeyframe: its features (landmark_ids optional,
/// empty = none) and which of them are static; the loop closer keeps the static ones only.
struct LoopKeyframeInput : LoopKeyframe {
  /// Per keypoint: 1 = static. 0 for every keypoint in a masked or held pixel, on a detected
  /// mover or on a landmark marked bad: those are dropped and never become loop evidence.
  std::vector<std::uint8_t> is_static;
  /// The newest LoopCorrection::generation the tracker had applied to T_W_C (0 = none yet).
  int generation = 0;
};

/// A keyframe moved by close(): landmarks anchored to it move with it,
/// p_W_after = correction() * p_W_before.
struct PoseCorrection {
  std::uint64_t id = 0;
  Eigen::Isometry3d T_W_C_before = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_W_C_after = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d correction() const { return T_W_C_after * T_W_C_before.inverse(); }
};

struct LoopCorrection {
  int generation = 0;  ///< pass it back in LoopKeyframeInput::generation once applied
  std::vector<PoseCorrection> keyframes;
};

/// Loop closure: place recognition over keyframes' static ORB features, geometric
/// verification of the candidates, an SE(3) pose graph over all keyframes (odometry edges
/// between consecutive keyframes, verified loop edges; the first keyframe fixed).
///
/// Threads: addKeyframe() and updatePose() are thread-safe and cheap (they queue under a short
/// lock): the tracking thread calls them. detect() and close() must be called from ONE thread
/// (the loop closer's own), which owns the keyframe database; they never block the queueing
/// calls for long. Timings ("loop_detect" per keyframe, "loop_close") go to `timings`.
///
/// Per keyframe, in order: tracker thread addKeyframe(); loop thread detect(); if it returned a
/// loop, loop thread close() -> the tracker applies each PoseCorrection to its keyframes and
/// their landmarks and the correction of the newest listed keyframe to everything newer
/// (current pose included), then passes the returned generation with its next keyframes.
/// Keyframes it added before applying are moved here the same way (by generation).
class LoopCloser {
 public:
  /// `timings` may be null; borrowed.
  LoopCloser(const PinholeCamera& camera, const TrackerConfig& tracker_config,
             const LoopCloserConfig& config, TimingRecorder* timings);

  void addKeyframe(LoopKeyframeInput keyframe);
  /// A keyframe moved by bundle adjustment (the pose in generation `generation`).
  void updatePose(std::uint64_t id, const Eigen::Isometry3d& T_W_C, int generation);
  /// Takes the queued keyframes into the database and looks for a loop for each; returns the
  /// newest verified loop, if any. Loop edges are kept for close().
  std::optional<LoopConstraint> detect();
  /// Optimises the pose graph with every loop edge found so far; empty when there is none.
  std::optional<LoopCorrection> close();

  std::size_t keyframeCount() const { return database_.size(); }  ///< loop thread only
  const std::vector<LoopConstraint>& loops() const { return loops_; }  ///< loop thread only

 private:
  struct PendingKeyframe {
    LoopKeyframe keyframe;
    int generation;
  };
  struct PoseInput {
    std::uint64_t id;
    Eigen::Isometry3d T_W_C;
    int generation;
  };
  Eigen::Isometry3d toCurrentGeneration(const Eigen::Isometry3d& T_W_C, int generation) const;
  void drainQueues();
  std::optional<LoopConstraint> detectFor(int index);
  std::vector<int> covisible(int index) const;

  PinholeCamera camera_;
  LoopCloserConfig config_;
  TimingRecorder* timings_;
  LoopVerifier verifier_;
  PlaceRecognizer recognizer_;

  std::mutex queue_mutex_;  ///< guards the three members below
  std::deque<PendingKeyframe> pending_;
  std::vector<PoseInput> pose_updates_;
  std::vector<Eigen::Isometry3d> generation_moves_;  ///< [g-1]: the move of generation g

  // Loop thread only.
  std::vector<LoopKeyframe> database_;
  std::vector<Eigen::Isometry3d> odometry_;  ///< [i]: T_Ci-1_Ci when keyframe i arrived
  std::unordered_map<std::uint64_t, int> index_of_;
  std::unordered_map<std::uint64_t, std::vector<int>> landmark_keyframes_;
  std::vector<LoopConstraint> loops_;
  std::size_t loops_closed_ = 0;
};

}  // namespace dynamap
