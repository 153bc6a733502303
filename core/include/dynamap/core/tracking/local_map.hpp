#pragma once

#include <cmath>
#include <cstdint>
#include <mutex>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/frame.hpp"
#include "dynamap/core/map_contents.hpp"
#include "dynamap/core/tracker.hpp"
#include "dynamap/core/tracking/landmark_search.hpp"
#include "dynamap/core/tracking/view_coverage.hpp"

namespace dynamap {

struct LoopCorrection;  // loop_closer.hpp

/// A copy of the sliding window handed to bundle adjustment (no lock held while solving).
struct BaWindow {
  struct Observation {
    int keyframe;  ///< index into keyframe_ids / poses
    int landmark;  ///< index into landmark_ids / points
    Eigen::Vector2d px;
    double depth_m;
    /// -1: seen by keyframe `keyframe` itself; otherwise by a keyframe culled into it, whose
    /// camera is attached[attached] (T_C_P: from the parent's camera) away from it.
    int attached = -1;
  };
  std::vector<std::uint64_t> keyframe_ids;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<std::uint8_t> fixed;
  /// Of each keyframe; NaN for a saved map's (its clock is another run's).
  std::vector<double> timestamps_s;
  std::vector<std::uint64_t> landmark_ids;
  std::vector<Eigen::Vector3d> points;
  std::vector<Observation> observations;
  std::vector<Eigen::Isometry3d> attached;
  int generation = 0;   ///< LocalMap::generation() when taken: a stale window is not applied
  bool global = false;  ///< every keyframe of the map (ba_global_every_keyframes)
};

/// Landmarks and keyframes shared by the tracking and BA threads. Every method is thread-safe;
/// each holds the lock only for a copy in or out. Ids are dense indices (never removed).
class LocalMap {
 public:
  std::uint64_t addLandmark(const Eigen::Vector3d& p_W, const cv::Mat& descriptor);
  std::uint64_t addKeyframe(double timestamp_s, const Eigen::Isometry3d& T_W_C,
                            std::vector<KeyframeObservation> observations,
                            double masked_share = 0.0, cv::Mat static_cells = cv::Mat());
  std::size_t keyframeCount() const;  ///< culled ones included (ids stay dense)
  /// Culls keyframe `id` into the older keyframe `parent` (MapKeyframe::culled): it follows
  /// `parent` rigidly from now on, and the windows of snapshotWindow() hold its observations as
  /// the parent's (BaWindow::Observation::attached). False (nothing changed) if either is culled,
  /// `parent` is not older, or `id` is 0 or loaded.
  bool cull(std::uint64_t id, std::uint64_t parent);
  bool isCulled(std::uint64_t id) const;
  Eigen::Isometry3d keyframePose(std::uint64_t id) const;
  /// Landmarks observed inside a dynamic region: left out of BA and relocalization from now on.
  void markBad(const std::vector<std::uint64_t>& ids);
  bool isBad(std::uint64_t id) const;
  /// out[i] = position of ids[i].
  void landmarkPositions(const std::vector<std::uint64_t>& ids,
                         std::vector<Eigen::Vector3d>& out) const;
  /// Row i of `descriptors` = the descriptor of ids[i]; bad[i] = 1 if it is marked bad.
  void descriptorsOf(const std::vector<std::uint64_t>& ids, cv::Mat& descriptors,
                     std::vector<std::uint8_t>& bad) const;
  /// out[i] = number of keyframes that observed ids[i].
  void keyframeCounts(const std::vector<std::uint64_t>& ids, std::vector<int>& out) const;

  /// The newest `window` keyframes; the oldest `fixed` of them and up to `window` older ones
  /// that see the same landmarks are held fixed, and so are up to `older_covisible` keyframes
  /// older than those, made `older_min_age_s` or more before the newest, that see the same
  /// landmarks (those sharing the most: a revisit found them again).
  BaWindow snapshotWindow(int window, int fixed, int older_covisible = 0,
                          double older_min_age_s = 0.0) const;
  /// Writes optimised poses and points back; returns the moved keyframes. A window taken
  /// before a loop correction (solved.generation != generation()) is dropped: nothing moves.
  std::vector<PoseUpdate> apply(const BaWindow& solved);
  /// Moves every keyframe by the loop correction (each listed keyframe by its own correction,
  /// those newer than the newest listed by that one's) and each landmark with its anchor (the
  /// first keyframe that observed it); generation() becomes correction.generation. Returns
  /// the keyframes' new poses.
  std::vector<PoseUpdate> applyLoopCorrection(const LoopCorrection& correction);
  int generation() const;  ///< the newest loop correction applied (0 = none)

  /// The newest `count` keyframes not culled, the newest first.
  std::vector<std::uint64_t> newestKeyframes(int count) const;
  std::vector<KeyframeInfo> keyframes() const;

  /// Keyframes not culled whose pose is within `max_translation_m` and `max_rotation_deg` of
  /// T_W_C, made at `latest_s` or before, the nearest first (by the larger of the two distances,
  /// each over its limit).
  std::vector<std::uint64_t> keyframesNear(const Eigen::Isometry3d& T_W_C, double max_translation_m,
                                           double max_rotation_deg,
                                           double latest_s = INFINITY) const;
  /// The good landmarks those keyframes observed, each once, in the keyframes' order.
  LandmarkCandidates landmarksOf(const std::vector<std::uint64_t>& keyframe_ids) const;
  std::size_t observationCount(std::uint64_t keyframe_id) const;
  /// A copy of everything but the culled keyframes, renumbered densely (a saved map's tracker
  /// part).
  MapContents contents() const;
  /// Replaces the contents with a saved map's, its keyframes marked loaded (fixed in bundle
  /// adjustment, old enough for any revisit). Ids must be dense (MapContents).
  void restore(MapContents contents);
  /// Poses and static cells of these keyframes (view_coverage.hpp).
  std::vector<CoverageView> coverageViews(const std::vector<std::uint64_t>& keyframe_ids) const;

 private:
  LandmarkCandidates landmarksOfLocked(const std::vector<std::uint64_t>& keyframe_ids) const;
  /// Culled keyframes back on their parents' poses; appends an update for each that moved to
  /// `updates` (may be null).
  void followParentsLocked(std::vector<PoseUpdate>* updates);
  std::vector<int> olderCovisibleLocked(
      int first, int limit, double min_age_s,
      const std::unordered_map<std::uint64_t, int>& lm_index) const;

  mutable std::mutex mutex_;
  std::vector<Landmark> landmarks_;
  std::vector<MapKeyframe> keyframes_;
  std::vector<std::uint64_t> culled_;  ///< culled keyframes, in culling order
  int generation_ = 0;
};

}  // namespace dynamap
