#include "dynamap/core/dynamic/region_fusion.hpp"

#include "dynamap/core/dynamic/depth_check.hpp"
#include "fusion_clusters.hpp"
#include "object_state.hpp"

#include <algorithm>
#include <cstdint>

#include <opencv2/imgproc.hpp>

namespace dynamap {

namespace {

/// An anchored point's surface must be continuous this far around it (an LK window of 15 px and
/// then some; windowInteriorDepth()) ...
constexpr int kAnchorWindowPx = 8;
constexpr float kAnchorWindowM = 0.1f;        ///< ... within this depth step
constexpr float kMatchIou = 0.3f;             ///< a detection continues a track above this IoU
constexpr float kUnderPersonShare = 0.3f;     ///< underPerson(): share of its box a person covers
constexpr int kMoverMinProven = 8;            ///< provenStaticMover(): proven-static points,
constexpr int kMoverProvenShareInverse = 10;  ///< ... and at least 1/10 of its points
constexpr float kSameObjectIou = 0.6f;        ///< two labels of one object (oneLabelPerObject)
/// rememberEndedStill(): still this many times static_confirm_frames, without slow moves (a
/// swayer at the end of a sway is still for a moment) ...
constexpr int kRememberQuietFactor = 4;
constexpr int kRememberSharedInverse = 4;  ///< ... and found again with a quarter of its points

/// The world position (evidence.T_W_C) of the centroid of `region`'s pixels in `box` at depth
/// `depth_m`; false (and *p_W untouched) if the box holds none of them.
bool worldCentroid(const cv::Mat& region, const cv::Rect& box, double depth_m,
                   const FusionEvidence& evidence, cv::Vec3d* p_W) {
  // cv::moments' m00, m10, m01 of the binary region: sums of whole numbers, exact in either
  // form; the other seven moments are not needed.
  std::int64_t m00 = 0, m10 = 0, m01 = 0;
  for (int y = 0; y < box.height; ++y) {
    const uchar* row = region.ptr<uchar>(box.y + y) + box.x;
    std::int64_t count = 0, sum_x = 0;
    for (int x = 0; x < box.width; ++x) {
      const int on = row[x] != 0 ? 1 : 0;
      count += on;
      sum_x += on * x;
    }
    m00 += count, m10 += sum_x, m01 += count * y;
  }
  if (m00 <= 0) return false;
  const double u = box.x + static_cast<double>(m10) / static_cast<double>(m00);
  const double v = box.y + static_cast<double>(m01) / static_cast<double>(m00), z = depth_m;
  const cv::Vec4d& K = evidence.K;
  const cv::Vec4d p_C((u - K[2]) / K[0] * z, (v - K[3]) / K[1] * z, z, 1.0);
  const cv::Vec4d p = evidence.T_W_C * p_C;
  *p_W = cv::Vec3d(p[0], p[1], p[2]);
  return true;
}

/// Counts the points on `region` (and the dynamic ones) into d; with point ids and a pose,
/// checks them against the anchors of `prev` (its track, may be null) into d.anchor.
void countPointsOn(const cv::Mat& region, const cv::Mat& depth_m,
                   const std::vector<cv::Point2f>& points, const std::vector<std::uint8_t>& dyn,
                   const FusionEvidence& evidence, const ObjectTrack* prev, ObjectDecision& d) {
  const bool with_ids = evidence.has_pose && evidence.point_ids.size() == points.size();
  std::vector<PointSample> samples;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!insideMask(region, points[i])) continue;
    ++d.points;
    if (dyn[i]) ++d.dynamic_points;
    if (i < evidence.proven_static.size() && evidence.proven_static[i] != 0) ++d.proven_points;
    if (with_ids) {
      samples.push_back({evidence.point_ids[i], points[i],
                         windowInteriorDepth(depth_m, cvRound(points[i].x), cvRound(points[i].y),
                                             kAnchorWindowPx, kAnchorWindowM)});
    }
  }
  if (with_ids) {
    static const std::vector<PointAnchor> kNone;
    d.anchor =
        checkAnchors(prev != nullptr ? prev->anchors : kNone, samples, evidence.T_W_C, evidence.K);
  }
}

/// The object's surface sampled now, and checked against the one kSurfaceBaselineFrames back
/// (prev's) into d.anchor.
void checkSurfaceOf(const cv::Mat& region, const cv::Mat& depth_m, const FusionEvidence& evidence,
                    const ObjectTrack* prev, ObjectDecision& d) {
  constexpr int kSurfaceStridePx = 8;
  constexpr double kSurfaceMaxDzM = 0.15;  ///< farther off is another surface (an occluder)
  d.anchor.surface_fresh = std::make_shared<const std::vector<cv::Vec3f>>(
      sampleSurface(region, depth_m, evidence.T_W_C, evidence.K, kSurfaceStridePx));
  if (prev != nullptr && prev->surfaces.size() >= kSurfaceBaselineFrames) {
    checkSurface(*prev->surfaces.front(), region, depth_m, evidence.T_W_C, evidence.K,
                 kSurfaceMaxDzM, &d.anchor);
  }
}

/// FusionEvidence::point_ids of the points inside `region` (empty without ids).
std::vector<std::uint64_t> idsIn(const cv::Mat& region, const std::vector<cv::Point2f>& points,
                                 const FusionEvidence& evidence) {
  std::vector<std::uint64_t> ids;
  if (evidence.point_ids.size() != points.size()) return ids;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (insideMask(region, points[i])) ids.push_back(evidence.point_ids[i]);
  }
  return ids;
}

/// FusionResult with every mask allocated (all zero) at `size`.
FusionResult emptyResult(const cv::Size& size) {
  FusionResult result;
  result.unconfirmed = cv::Mat::zeros(size, CV_8UC1);
  result.held = cv::Mat::zeros(size, CV_8UC1);
  result.mask = cv::Mat::zeros(size, CV_8UC1);
  result.static_objects = cv::Mat::zeros(size, CV_8UC1);
  return result;
}

}  // namespace

/// One fuse() call: its inputs, and the masks it builds besides FusionResult's.
struct RegionFusion::Frame {
  FusionMode mode;
  const cv::Mat& depth_m;
  const std::vector<cv::Point2f>& points;
  const std::vector<std::uint8_t>& dyn;
  const FusionEvidence& evidence;
  cv::Mat confirmed;  ///< pixels of objects confirmed static over time
  cv::Mat certain;    ///< moving pixels with evidence of their own
  cv::Mat evidenced;  ///< pixels of objects masked for motion
  cv::Mat claimed;    ///< pixels of detected objects (clusters do not grow into them)
  cv::Mat movers;     ///< pixels of moving movers (ClassTable::kMover): geometry saw them move
  cv::Mat people;     ///< pixels of detected high-dynamic objects (no mover takes them)
  cv::Mat things;     ///< pixels of moving objects that are not people (movers, a pushed chair)
};

RegionFusion::RegionFusion(const DynamicConfig& config, const ClassTable& classes)
    : config_(config), classes_(classes) {}

void RegionFusion::propagateTracks(const std::vector<cv::Point2f>& points,
                                   const FusionEvidence& evidence) {
  if (evidence.prev_points.size() != points.size()) return;
  for (auto& t : tracks_) {
    cv::Point2f flow;
    if (medianFlowIn(t.box, evidence.prev_points, points, &flow)) t.box += flow;
  }
}

cv::Mat RegionFusion::depthCut(const Frame& f, const cv::Rect& box, ObjectDecision& d,
                               const ObjectTrack* prev) const {
  const double prior = prev != nullptr ? prev->depth_m : 0.0;
  // A carried box at the image border may have lost its object through the border: then it is
  // the object only at the object's own depth, not at whatever its centre shows now.
  const cv::Mat& depth_m = f.depth_m;
  const bool at_border =
      box.x <= 0 || box.y <= 0 || box.br().x >= depth_m.cols || box.br().y >= depth_m.rows;
  const bool prior_only = d.carried && at_border && config_.carried_border_exit;
  // A person is no taller than person_max_height_m: a box h pixels tall holds one no farther
  // than that height seen over h pixels (the box may be cut by the border: then nearer still).
  static const int kPerson = ClassTable::classIndex("person");
  const double fy = f.evidence.K[1];
  const double max_depth =
      d.detection.class_id == kPerson && config_.person_max_height_m > 0.0 && fy > 0.0
          ? config_.person_max_height_m * fy / box.height
          : 0.0;
  // A mover's box is its seen-through region's: its surface is as deep as that region was grown
  // (dense_depth_range_m), not a person's depth band (the teddy beside a pushed chair).
  const double band = d.detection.class_id == ClassTable::kMover ? config_.dense_depth_range_m
                                                                 : config_.depth_band_m;
  cv::Mat region =
      objectPixels(depth_m, box, band, &d.depth_m, prior, f.evidence.planes, prior_only, max_depth);
  if (region.empty()) {
    region = cv::Mat::zeros(depth_m.size(), CV_8UC1);
    region(box).setTo(255);
  }
  return region;
}

cv::Mat RegionFusion::objectRegion(const Frame& f, const cv::Rect& box, ObjectDecision& d,
                                   const ObjectTrack* prev) const {
  cv::Mat region = depthCut(f, box, d, prev);
  if (f.evidence.has_pose && d.depth_m > 0.0 &&
      worldCentroid(region, box, d.depth_m, f.evidence, &d.p_W)) {
    d.has_position = true;
  }
  countPointsOn(region, f.depth_m, f.points, f.dyn, f.evidence, prev, d);
  // People sway on the spot; a pushed chair or box moves and stops, judged by its anchors.
  if (config_.static_surface_m > 0.0 && f.evidence.has_pose &&
      classes_.isDetectedHighDynamic(d.detection.class_id)) {
    checkSurfaceOf(region, f.depth_m, f.evidence, prev, d);
  }
  return region;
}

cv::Mat RegionFusion::detectedRegion(const Frame& f, const cv::Rect& box, ObjectDecision& d,
                                     int& track, const ObjectTrack** remembered) const {
  *remembered = nullptr;
  const ObjectTrack* prev = track >= 0 ? &tracks_[track] : nullptr;
  cv::Mat region = objectRegion(f, box, d, prev);
  if (prev != nullptr || f.mode != FusionMode::kBoth) return region;
  // No box overlaps it enough; the points on it may still be an earlier track's ...
  const std::vector<std::uint64_t> ids = idsIn(region, f.points, f.evidence);
  track = trackSharingPoints(ids, tracks_, d.detection.class_id, kAnchorMinPoints);
  if (track >= 0) {
    d = newDecision(d.detection);
    return objectRegion(f, box, d, &tracks_[track]);
  }
  // ... or a still object's that was hidden for a while (its anchors judge it as before).
  const int shared =
      std::max(kAnchorMinPoints, static_cast<int>(ids.size()) / kRememberSharedInverse);
  const int r = trackSharingPoints(ids, remembered_, d.detection.class_id, shared);
  if (r < 0) return region;
  *remembered = &remembered_[static_cast<std::size_t>(r)];
  d = newDecision(d.detection);
  return objectRegion(f, box, d, *remembered);
}

bool RegionFusion::carried(std::size_t t, const cv::Size& image) const {
  const ObjectTrack& track = tracks_[t];
  return track.missed < config_.track_max_missed_frames &&
         clampRect(track.box, image).area() * 4 >= track.box.area();
}

void RegionFusion::rememberEndedStill(const std::vector<bool>& matched, const cv::Size& image) {
  for (std::size_t k = remembered_.size(); k-- > 0;) {
    if (remembered_until_[k] > frame_) continue;
    remembered_.erase(remembered_.begin() + static_cast<std::ptrdiff_t>(k));
    remembered_until_.erase(remembered_until_.begin() + static_cast<std::ptrdiff_t>(k));
  }
  if (config_.remember_still_frames <= 0) return;
  for (std::size_t t = 0; t < tracks_.size(); ++t) {
    const ObjectTrack& track = tracks_[t];
    const bool ended = !(t < matched.size() && matched[t]) && !carried(t, image);
    if (ended && !track.moving && track.slow_moves == 0 &&
        track.quiet_frames >= kRememberQuietFactor * config_.static_confirm_frames &&
        classes_.isDetectedHighDynamic(track.class_id) &&
        static_cast<int>(track.anchors.size()) >= kAnchorMinPoints) {
      remembered_.push_back(track);
      remembered_until_.push_back(frame_ + config_.remember_still_frames);
    }
  }
}

void RegionFusion::applyObject(Frame& f, ObjectDecision& d, cv::Mat& region, const cv::Rect& box,
                               FusionResult& result) const {
  // A person's pixels are his track's to judge: a mover's box beside him does not take them.
  const bool mover = d.detection.class_id == ClassTable::kMover;
  if (mover) region(box).setTo(0, f.people(box));
  if (!mover && classes_.isHighDynamic(d.detection.class_id)) f.people(box) |= region(box);
  f.claimed(box) |= region(box);
  if (d.moving && f.mode == FusionMode::kBoth) {
    carveStatic(region, box, f.points, f.dyn, f.evidence.proven_static,
                config_.static_carve_radius_px);
  }
  // The region lies in its box: only the box of each mask is touched.
  const cv::Mat in_box = region(box);
  const auto add = [&](const cv::Mat& mask) {  // writes into mask's pixels
    cv::Mat roi = mask(box);
    roi |= in_box;
  };
  add(d.moving ? result.mask : result.static_objects);
  if (d.moving && mover) add(f.movers);
  if (d.moving && (mover || !classes_.isHighDynamic(d.detection.class_id))) add(f.things);
  if (d.moving) add(d.unconfirmed ? result.unconfirmed : f.certain);
  if (d.moving) add(d.motion_now || f.mode != FusionMode::kBoth ? f.evidenced : result.held);
  if (!d.moving && d.quiet_frames >= config_.static_confirm_frames) add(f.confirmed);
  result.objects.push_back(d);
}

bool RegionFusion::underPerson(const Detection& object,
                               const std::vector<Detection>& detections) const {
  if (classes_.isHighDynamic(object.class_id)) return false;
  const float area = object.box.area();
  const auto covers = [&](int class_id, const cv::Rect2f& box) {
    return classes_.isDetectedHighDynamic(class_id) && area > 0.f &&
           (box & object.box).area() >= kUnderPersonShare * area;
  };
  for (const auto& o : detections)
    if (covers(o.class_id, o.box)) return true;
  for (const auto& t : tracks_)  // people not detected in this frame, their boxes moved by the flow
    if (covers(t.class_id, t.box)) return true;
  return false;
}

bool RegionFusion::provenStaticMover(const ObjectDecision& d) const {
  // A mover (a seen-through region grown into its surface) that holds landmarks the pose from
  // proven-static landmarks kept in this frame, with their depth, is a static surface the check
  // saw through by mistake (the teddy at 0.7 m after a pose error: 48 of its 284 points), not
  // something that moved in: the pushed boxes, chairs and carts hold none. Also a mover track
  // that grew over such a surface (teddy_dyn_crowd_dev from frame 8: a region at the teddy's
  // foot grew over the teddy, a third of the view, masked 3 frames and the pose lost).
  return d.detection.class_id == ClassTable::kMover && d.proven_points >= kMoverMinProven &&
         d.proven_points * kMoverProvenShareInverse >= d.points;
}

ObjectDecision RegionFusion::newDecision(const Detection& detection) const {
  ObjectDecision d;
  d.detection = detection;
  d.weight = classes_.weight(detection.class_id);
  return d;
}

std::vector<Detection> RegionFusion::oneLabelPerObject(const std::vector<Detection>& in) const {
  std::vector<Detection> out;
  for (const auto& d : in) {
    bool relabelled = false;
    for (const auto& o : in) {
      relabelled = relabelled ||
                   (classes_.isHighDynamic(d.class_id) && !classes_.isHighDynamic(o.class_id) &&
                    o.score > d.score && iou(d.box, o.box) >= kSameObjectIou);
    }
    if (!relabelled) out.push_back(d);
  }
  return out;
}

std::vector<bool> RegionFusion::fuseDetections(Frame& f, const std::vector<Detection>& detections,
                                               std::vector<ObjectTrack>& next,
                                               FusionResult& result) const {
  const std::vector<int> track_of = associateDetections(detections, tracks_, kMatchIou);
  std::vector<bool> matched(tracks_.size(), false);
  for (std::size_t k = 0; k < detections.size(); ++k) {
    ObjectDecision d = newDecision(detections[k]);
    if (d.weight <= 0.0) continue;
    if (f.mode == FusionMode::kDetector && !classes_.isHighDynamic(d.detection.class_id)) continue;
    const cv::Rect box = clampRect(d.detection.box, f.depth_m.size());
    if (box.area() <= 0) continue;
    int track = track_of[k];
    d.under_person = underPerson(d.detection, detections);
    const ObjectTrack* remembered = nullptr;
    cv::Mat region = detectedRegion(f, box, d, track, &remembered);
    if (provenStaticMover(d)) {
      if (track >= 0) matched[track] = true;  // its track ends: not carried either
      continue;
    }
    if (f.mode == FusionMode::kDetector) {
      d.moving_now = d.moving = true;
    } else {
      const ObjectTrack* prev = track >= 0 ? &tracks_[track] : remembered;
      if (track >= 0) matched[track] = true;
      next.push_back(nextObjectState(d, prev, f.evidence, config_,
                                     classes_.isHighDynamic(d.detection.class_id)));
    }
    applyObject(f, d, region, box, result);
  }
  return matched;
}

void RegionFusion::carryUndetected(Frame& f, const std::vector<bool>& matched,
                                   const std::vector<Detection>& detections,
                                   std::vector<ObjectTrack>& next, FusionResult& result) const {
  for (std::size_t t = 0; t < tracks_.size(); ++t) {
    const ObjectTrack& track = tracks_[t];
    const cv::Rect box = clampRect(track.box, f.depth_m.size());
    if (matched[t] || !carried(t, f.depth_m.size())) continue;
    ObjectDecision d = newDecision(Detection{track.box, track.class_id, 0.f});
    d.carried = true;
    d.under_person = underPerson(d.detection, detections);
    cv::Mat region = objectRegion(f, box, d, &track);
    next.push_back(nextObjectState(d, &track, f.evidence, config_,
                                   classes_.isHighDynamic(d.detection.class_id)));
    // A mover whose own points moved on (anchors off by twice the limit) is followed while the
    // depth check cannot see it: a box pushed straight away from the camera is never seen
    // through (mover_follow_anchors).
    const bool followed = config_.mover_follow_anchors && track.class_id == ClassTable::kMover &&
                          next.back().anchors_moved;
    next.back().missed = followed ? 0 : track.missed + 1;
    applyObject(f, d, region, box, result);
  }
}

void RegionFusion::finishMasks(Frame& f, FusionResult& result) const {
  // What has proven static over time is not another object's: a walker's box that covers the
  // teddy (or a standing person) must not take its depth cut.
  if (cv::countNonZero(f.confirmed) > 0) result.mask.setTo(0, f.confirmed);
  // ... unless the depth saw it move: a chair the detector knows, confirmed still, is pushed (a
  // person's pixels stay his own track's, also one carried after the movers were decided).
  cv::Mat pushed = f.movers.clone();
  pushed.setTo(0, f.people);
  result.mask |= pushed;
  if (f.mode != FusionMode::kDetector && f.evidence.flags_valid) {
    cv::Mat grown = cv::Mat::zeros(f.depth_m.size(), CV_8UC1);
    result.clusters =
        growClusters(f.depth_m, f.points, f.dyn, f.claimed, f.evidence, config_, grown);
    result.mask |= grown;
    f.certain |= grown;
    f.evidenced |= grown;
  }
  result.unconfirmed.setTo(0, f.certain | f.confirmed);
  result.confirmed = f.confirmed;
  result.moved_objects = f.things & result.mask;
  result.moved_objects.setTo(0, f.people);
  if (config_.mask_dilation_px > 0 && cv::countNonZero(result.mask) > 0) {
    const int k = 2 * config_.mask_dilation_px + 1;
    const cv::Mat disc = cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k});
    cv::dilate(result.mask, result.mask, disc);
    // The held margin is the held object's, but not where a moving object's margin reaches.
    cv::dilate(result.held, result.held, disc);
    cv::dilate(f.evidenced, f.evidenced, disc);
  }
  result.held.setTo(0, f.evidenced | f.confirmed);
}

FusionResult RegionFusion::fuse(FusionMode mode, const cv::Mat& depth_m,
                                const std::vector<cv::Point2f>& points,
                                const std::vector<std::uint8_t>& dyn,
                                const std::vector<Detection>& all_detections,
                                const FusionEvidence& evidence) {
  const auto zeros = [&depth_m] { return cv::Mat(cv::Mat::zeros(depth_m.size(), CV_8UC1)); };
  Frame f{mode,    depth_m, points,  dyn,     evidence, zeros(),
          zeros(), zeros(), zeros(), zeros(), zeros(),  zeros()};
  FusionResult result = emptyResult(depth_m.size());
  std::vector<ObjectTrack> next;
  if (mode != FusionMode::kGeometry) {
    propagateTracks(points, evidence);
    // A teddy bear that is also a 0.3 "person" is one object: the better-scored class wins.
    const std::vector<bool> matched =
        fuseDetections(f, oneLabelPerObject(all_detections), next, result);
    // Objects the detector did not report in this frame: a person seen a moment ago keeps its
    // mask (and its evidence) for a few frames, its box moved with the flow.
    if (mode == FusionMode::kBoth) carryUndetected(f, matched, all_detections, next, result);
    if (mode == FusionMode::kBoth) rememberEndedStill(matched, depth_m.size());
  }
  tracks_ = std::move(next);
  ++frame_;
  finishMasks(f, result);
  return result;
}

}  // namespace dynamap
