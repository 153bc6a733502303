#include "object_state.hpp"

#include "dynamap/core/dynamic/depth_check.hpp"

#include <algorithm>
#include <cmath>

namespace dynamap {

namespace {

constexpr int kStaticMinPoints = 5;    ///< points needed on an object to call it static now
constexpr int kMaxSlowDoublings = 4;   ///< ObjectTrack::slow_moves: at most 16 x the frames
constexpr int kSurfaceMinPoints = 30;  ///< surface points needed to judge an object by them

/// What an object's own points, followed over time, say in this frame: against the pose from
/// landmarks proven static they are within the pose noise (still), clearly off (twice that) or
/// in between (no verdict).
enum class AnchorVerdict {
  kNone,       ///< too few anchored points, or no still limit: the anchors say nothing
  kStill,      ///< within the still limit
  kUndecided,  ///< beyond the still limit, within twice it
  /// Beyond twice it, but the person was confirmed still with still anchors: a jump from within
  /// the still limit in one frame (a pose error, or the semi-synthetic sequences' ground-truth
  /// jitter) is masked in this frame only; the count and the anchors restart only when the next
  /// frame sees them off again (static_anchor_move_frames).
  kJumpHeld,
  kMoved,  ///< beyond twice it: the object moved
};

/// This frame's evidence on one object.
struct Observation {
  bool observed = false;  ///< flags valid and enough points on the object
  double evidence = 0.0;  ///< class prior x share of dynamic points on its own pixels
  bool flagged = false;   ///< its flags say it moves (whatever its anchors say)
  bool quiet = false;     ///< enough points on it, few of them dynamic
  AnchorVerdict anchors = AnchorVerdict::kNone;
  bool confirmed_before = false;  ///< counted still, and not moving, in the last frame

  bool anchored() const { return anchors != AnchorVerdict::kNone; }
  /// Flags the anchors do not confirm were measured against a wrong camera motion: they mask
  /// the object in this frame but restart neither its quiet count nor its anchors.
  bool movingNow() const { return flagged && !(anchored() && anchors != AnchorVerdict::kMoved); }
};

bool countedStill(const ObjectTrack* prev, const DynamicConfig& c) {
  return prev != nullptr && prev->quiet_frames >= c.static_confirm_frames;
}

/// The still limit of an object's anchors in pixels: the pose noise, or a still person's
/// postural sway (static_anchor_m) seen at its depth, whichever is larger (0 = none).
double stillLimitPx(const ObjectDecision& d, const cv::Vec4d& K, const DynamicConfig& c) {
  const double sway_px = d.depth_m > 0.0 && K[0] > 0.0 ? c.static_anchor_m * K[0] / d.depth_m : 0.0;
  return c.static_anchor_px > 0.0 ? std::max(c.static_anchor_px, sway_px) : 0.0;
}

/// Enough of its surface of kSurfaceBaselineFrames back lands on the object now to judge it.
bool surfaceJudged(const ObjectDecision& d, const DynamicConfig& c) {
  return c.static_surface_m > 0.0 && d.anchor.surface_points >= kSurfaceMinPoints;
}

/// Its anchors are off by twice the still limit, and by more than the sensor's depth noise
/// could make them (3 sigma of the difference of two depths): a wall 4 m away is no mover.
bool movedBeyondNoise(const ObjectDecision& d, const cv::Vec4d& K, const DynamicConfig& c) {
  const double noise_z = 3.0 * std::sqrt(2.0) * depthNoiseM(d.depth_m);
  return d.anchor.median_px > 2.0 * stillLimitPx(d, K, c) ||
         std::abs(d.anchor.median_dz_m) > 2.0 * std::max(c.static_anchor_depth_m, noise_z) ||
         (surfaceJudged(d, c) && std::abs(d.anchor.surface_dz_m) > 2.0 * c.static_surface_m);
}

/// The verdict of one measure against its still limit `tau` (beyond twice it: moved).
AnchorVerdict againstLimit(double off, double tau) {
  if (off <= tau) return AnchorVerdict::kStill;
  return off > 2.0 * tau ? AnchorVerdict::kMoved : AnchorVerdict::kUndecided;
}

/// The worse of what its anchored points and its surface say (either may say nothing).
AnchorVerdict judgeAnchors(const ObjectDecision& d, const ObjectTrack* prev, const cv::Vec4d& K,
                           const DynamicConfig& c) {
  AnchorVerdict verdict = AnchorVerdict::kNone;
  const double tau = stillLimitPx(d, K, c);
  if (tau > 0.0 && d.anchor.points >= kAnchorMinPoints) {
    verdict = std::max(againstLimit(d.anchor.median_px, tau),
                       againstLimit(std::abs(d.anchor.median_dz_m), c.static_anchor_depth_m));
  }
  // The surface only adds motion: alone it calls nothing still (an object with too few anchored
  // points to judge is judged by its centroid, which a walker drifts out of).
  if (surfaceJudged(d, c)) {
    const AnchorVerdict surface = againstLimit(std::abs(d.anchor.surface_dz_m), c.static_surface_m);
    if (verdict != AnchorVerdict::kNone || surface != AnchorVerdict::kStill) {
      verdict = std::max(verdict, surface);
    }
  }
  if (verdict != AnchorVerdict::kMoved) return verdict;
  const bool held = c.static_anchor_move_frames > 1 && countedStill(prev, c) && prev->anchors_still;
  return held ? AnchorVerdict::kJumpHeld : AnchorVerdict::kMoved;
}

Observation observe(const ObjectDecision& d, const ObjectTrack* prev, const FusionEvidence& ev,
                    const DynamicConfig& c) {
  Observation obs;
  obs.observed = ev.flags_valid && d.points >= c.min_object_points;
  obs.evidence = obs.observed ? d.weight * d.dynamic_points / d.points : 0.0;
  obs.flagged =
      obs.observed && d.dynamic_points >= c.min_dynamic_points && obs.evidence >= c.moving_ratio;
  obs.quiet = obs.observed && d.points >= kStaticMinPoints &&
              d.dynamic_points <= c.static_max_dynamic_share * d.points;
  obs.anchors = judgeAnchors(d, prev, ev.K, c);
  obs.confirmed_before = countedStill(prev, c) && !prev->moving;
  return obs;
}

/// The new track: where the object is, and its slow moves (anchors off without flags).
ObjectTrack startTrack(const ObjectDecision& d, const ObjectTrack* prev, const Observation& obs,
                       const DynamicConfig& c) {
  ObjectTrack t;
  t.box = d.detection.box;
  t.depth_m = d.depth_m > 0.0 || prev == nullptr ? d.depth_m : prev->depth_m;
  t.anchors_still = obs.anchors == AnchorVerdict::kStill;
  t.class_id = d.detection.class_id;
  // A depth cut that jumped is another surface (the track went to another object): it starts
  // with no slow moves.
  const bool jumped = prev != nullptr && d.depth_m > 0.0 && prev->depth_m > 0.0 &&
                      std::abs(d.depth_m - prev->depth_m) >= c.depth_band_m;
  const bool slow_move = obs.anchors == AnchorVerdict::kMoved && !obs.flagged && !jumped;
  t.slow_moves = (prev != nullptr && !jumped ? prev->slow_moves : 0) + (slow_move ? 1 : 0);
  // Its surfaces of the last frames: a depth cut that jumped starts them over.
  if (prev != nullptr && !jumped) t.surfaces = prev->surfaces;
  if (d.anchor.surface_fresh && !d.anchor.surface_fresh->empty()) {
    t.surfaces.push_back(d.anchor.surface_fresh);
  }
  while (t.surfaces.size() > kSurfaceBaselineFrames) t.surfaces.pop_front();
  return t;
}

/// Temporal hysteresis: the smoothed evidence must reach moving_ratio (with enough dynamic
/// points now) to turn the object moving; it stays moving until it falls below half of it.
/// Clear static evidence counts twice (a faster release). Unobserved frames keep the state.
void smoothEvidence(ObjectTrack& t, const ObjectTrack* prev, const Observation& obs,
                    const DynamicConfig& c) {
  const double a = c.evidence_smoothing;
  t.score = obs.evidence;
  if (prev != nullptr) {
    t.score = obs.observed ? a * prev->score + (1.0 - a) * obs.evidence : prev->score;
  }
  const bool was_moving = prev != nullptr && prev->moving;
  t.moving =
      was_moving ? t.score >= 0.5 * c.moving_ratio : (obs.movingNow() && t.score >= c.moving_ratio);
  if (prev != nullptr && obs.quiet) {
    t.score = a * t.score + (1.0 - a) * obs.evidence;
    t.moving = was_moving && t.score >= 0.5 * c.moving_ratio;
  }
}

/// Keeping a person takes evidence gathered over time, measured against a camera motion fitted
/// without it; one frame of clear motion removes it again. Counts the quiet frames and keeps
/// (or restarts) the anchors and the world position they are counted from.
void countQuietFrames(ObjectTrack& t, const ObjectDecision& d, const ObjectTrack* prev,
                      const Observation& obs, bool background_fit, const DynamicConfig& c) {
  int before = prev != nullptr ? prev->quiet_frames : 0;
  if (prev != nullptr && prev->has_anchor) t.has_anchor = true, t.anchor_W = prev->anchor_W;
  bool still = false;  // its world position stayed put (camera pose from proven landmarks)
  // A frame without a pose checks no anchors: it keeps them. Dropped there, the teddy (taken for
  // a person) of teddy x10 at a turn lost them in two frames without a pose, was judged on its
  // centroid, which had drifted with the view, restarted its count and was masked.
  t.anchors = d.anchor.checked || prev == nullptr ? d.anchor.kept : prev->anchors;
  if (obs.anchored()) {
    // Its own points, followed over time, tell better than its centroid.
    still = obs.anchors == AnchorVerdict::kStill;
    if (obs.anchors == AnchorVerdict::kMoved) {
      t.anchors = d.anchor.fresh, before = 0;
      t.has_anchor = d.has_position, t.anchor_W = d.p_W;
    }
  } else if (d.has_position && c.static_max_drift_m > 0.0) {
    // Frame-to-frame checks cannot see a slow walker (a pixel a frame): its world position can.
    if (!t.has_anchor || cv::norm(d.p_W - t.anchor_W) > c.static_max_drift_m) {
      t.has_anchor = true, t.anchor_W = d.p_W, before = 0;
    } else {
      still = true;
    }
  }
  // Static evidence of this frame: its points agree with the background's motion, or, when it
  // has too few points to tell (a plain jacket, the depth-less border), its world position.
  const bool few_points = d.points < kStaticMinPoints;
  const bool evidence_now = obs.anchored() ? obs.anchors == AnchorVerdict::kStill
                                           : (obs.quiet && background_fit) || (few_points && still);
  t.quiet_frames = obs.movingNow() ? 0 : before + (evidence_now ? 1 : 0);
  if (obs.movingNow()) t.has_anchor = false, t.anchors = d.anchor.fresh;
}

/// A person is masked until he has shown, for long enough, that he stands still; anchors off by
/// more than the pose noise mask him in this frame (his count is kept).
void holdUntilConfirmed(ObjectTrack& t, ObjectDecision& d, const Observation& obs,
                        const DynamicConfig& c) {
  const int needed = c.static_confirm_frames << std::min(t.slow_moves, kMaxSlowDoublings);
  const bool evidenced = t.moving || (obs.anchored() && obs.anchors != AnchorVerdict::kStill);
  t.moving = evidenced || t.quiet_frames < needed;
  d.unconfirmed =
      t.moving && !evidenced && !obs.flagged && t.slow_moves == 0 && t.score < c.moving_ratio;
}

/// An object of another class that was seen to move stays masked until it has stood still for
/// static_confirm_frames (hold_moved_objects): a pushed chair flags few points while it moves
/// away from the camera, but its anchors drift off frame after frame. While held, anchors off by
/// less than twice the limit start a new run from where it is now: it moved on since they were
/// set, or stopped just there (else it would stay held for ever). A walker passing in front of a
/// chair moves its points and flags: under a person's box, nothing starts a hold.
void holdMovedUntilStill(ObjectTrack& t, const ObjectDecision& d, const ObjectTrack* prev,
                         const Observation& obs, const DynamicConfig& c) {
  const bool held_before = prev != nullptr && prev->seen_moving;
  if (held_before && obs.anchors == AnchorVerdict::kUndecided) {
    t.anchors = d.anchor.fresh;
    t.quiet_frames = 0;
  }
  // Under a person's box its points and flags may be the person's: that starts no hold.
  const bool moved_now = !d.under_person && (t.moving || obs.anchors == AnchorVerdict::kMoved);
  t.seen_moving = moved_now || (held_before && t.quiet_frames < c.static_confirm_frames);
  t.moving = t.moving || t.seen_moving;
}

}  // namespace

ObjectTrack nextObjectState(ObjectDecision& d, const ObjectTrack* prev,
                            const FusionEvidence& evidence, const DynamicConfig& config,
                            bool high_dynamic) {
  const Observation obs = observe(d, prev, evidence, config);
  d.moving_now = obs.movingNow();
  ObjectTrack t = startTrack(d, prev, obs, config);
  t.anchors_moved = obs.anchors == AnchorVerdict::kMoved && movedBeyondNoise(d, evidence.K, config);
  smoothEvidence(t, prev, obs, config);
  countQuietFrames(t, d, prev, obs, evidence.background_fit, config);
  // A person confirmed still whose flags his anchors do not confirm (they drifted, but less than
  // twice the pose noise) is masked now but held: hindsight may keep him in the map.
  const bool moved = obs.anchors == AnchorVerdict::kMoved;
  const bool unconfirmed_flags = obs.confirmed_before && obs.anchored() && !moved;
  d.motion_now = (obs.flagged && !unconfirmed_flags) || moved || t.moving;
  if (high_dynamic) holdUntilConfirmed(t, d, obs, config);
  if (!high_dynamic && config.hold_moved_objects) holdMovedUntilStill(t, d, prev, obs, config);
  d.moving = t.moving;
  d.quiet_frames = t.quiet_frames;
  return t;
}

}  // namespace dynamap
