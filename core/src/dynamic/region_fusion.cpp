#include "dynamap/core/dynamic/region_fusion.hpp"

#include "dynamap/core/dynamic/depth_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>

#include <opencv2/imgproc.hpp>

namespace dynamap {

namespace {

constexpr double kBinM = 0.1;
constexpr int kStaticMinPoints = 5;   ///< points needed on an object to call it static now
constexpr int kAnchorMinPoints = 3;   ///< anchored points needed for the anchor test
constexpr int kMaxSlowDoublings = 4;  ///< ObjectTrack::slow_moves: at most 16 x the frames
/// An anchored point's surface must be continuous this far around it (an LK window of 15 px and
/// then some; windowInteriorDepth()) ...
constexpr int kAnchorWindowPx = 8;
constexpr float kAnchorWindowM = 0.1f;  ///< ... within this depth step
constexpr int kBins = 100;              // 0..10 m
constexpr float kMatchIou = 0.3f;       ///< a detection continues a track above this IoU
constexpr float kSameObjectIou = 0.6f;  ///< two labels of one object (oneLabelPerObject)
constexpr int kInPlaceMinSamples = 20;  ///< depth samples needed to call a cluster in place

/// Dominant depth (m) of the valid pixels of `roi`, 0 if there are too few. With `near_m` > 0
/// only depths within kContinuityM of it compete (the object was there a frame ago). `dropped`
/// (8-bit, roi's size, or empty): pixels read as 0, not the object's.
constexpr double kContinuityM = 0.5;
double depthMode(const cv::Mat& roi, double near_m, const cv::Mat& dropped = cv::Mat()) {
  const bool any_dropped = !dropped.empty();
  const auto value = [&](const float* z_row, const uchar* dropped_row, int x) {
    return any_dropped && dropped_row[x] != 0 ? 0.f : z_row[x];
  };
  std::vector<int> hist(kBins + 2, 0);
  int total = 0;
  for (int y = 0; y < roi.rows; y += 2) {
    const float* z_row = roi.ptr<float>(y);
    const uchar* dropped_row = any_dropped ? dropped.ptr<uchar>(y) : nullptr;
    for (int x = 0; x < roi.cols; x += 2) {
      const float z = value(z_row, dropped_row, x);
      const int b = static_cast<int>(z / kBinM);
      const bool near = near_m <= 0.0 || std::abs(z - near_m) < kContinuityM;
      if (z > 0.f && b < kBins && near) {
        ++hist[b + 1];
        ++total;
      }
    }
  }
  if (total < 20) return 0.0;
  int best = 1;
  for (int b = 1; b <= kBins; ++b) {
    if (hist[b - 1] + 2 * hist[b] + hist[b + 1] > hist[best - 1] + 2 * hist[best] + hist[best + 1])
      best = b;
  }
  const double lo = (best - 2) * kBinM, hi = (best + 1) * kBinM;  // the peak bin +- one bin
  std::vector<float> vals;
  for (int y = 0; y < roi.rows; y += 2) {
    const float* z_row = roi.ptr<float>(y);
    const uchar* dropped_row = any_dropped ? dropped.ptr<uchar>(y) : nullptr;
    for (int x = 0; x < roi.cols; x += 2) {
      const float z = value(z_row, dropped_row, x);
      if (z > lo && z < hi) vals.push_back(z);
    }
  }
  std::nth_element(vals.begin(), vals.begin() + vals.size() / 2, vals.end());
  return vals[vals.size() / 2];
}

bool inside(const cv::Mat& mask, const cv::Point2f& p) {
  const int x = cvRound(p.x), y = cvRound(p.y);
  return x >= 0 && y >= 0 && x < mask.cols && y < mask.rows && mask.at<uchar>(y, x) != 0;
}

int findRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

/// Groups the given points by single linkage with `radius`.
std::vector<std::vector<int>> clusterPoints(const std::vector<cv::Point2f>& pts,
                                            const std::vector<int>& ids, double radius) {
  std::vector<int> parent(ids.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t a = 0; a < ids.size(); ++a) {
    for (std::size_t b = a + 1; b < ids.size(); ++b) {
      if (cv::norm(pts[ids[a]] - pts[ids[b]]) <= radius) {
        parent[findRoot(parent, static_cast<int>(a))] = findRoot(parent, static_cast<int>(b));
      }
    }
  }
  std::vector<std::vector<int>> groups(ids.size());
  for (std::size_t a = 0; a < ids.size(); ++a)
    groups[findRoot(parent, static_cast<int>(a))].push_back(ids[a]);
  groups.erase(
      std::remove_if(groups.begin(), groups.end(), [](const auto& g) { return g.empty(); }),
      groups.end());
  return groups;
}

cv::Rect clampRect(const cv::Rect2f& r, const cv::Size& size) {
  return cv::Rect(cv::Point(cvFloor(r.x), cvFloor(r.y)),
                  cv::Point(cvCeil(r.br().x), cvCeil(r.br().y))) &
         cv::Rect(cv::Point(0, 0), size);
}

/// Removes from `region` (inside `box`) the pixels that are nearer, by more than kCarveMarginPx,
/// to a proven-static tracked point inside the region than to a dynamic one, and within `radius`
/// of it. Points neither dynamic nor proven static take no part.
constexpr float kCarveMarginPx = 4.f;
void carveStatic(cv::Mat& region, const cv::Rect& box, const std::vector<cv::Point2f>& points,
                 const std::vector<std::uint8_t>& dyn, const std::vector<std::uint8_t>& proven,
                 double radius) {
  if (radius <= 0.0 || box.area() <= 0) return;
  cv::Mat roi = region(box);
  cv::Mat dyn_free(box.size(), CV_8UC1, cv::Scalar(255));
  cv::Mat static_free(box.size(), CV_8UC1, cv::Scalar(255));
  int n_dyn = 0, n_static = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const cv::Point p(cvRound(points[i].x) - box.x, cvRound(points[i].y) - box.y);
    if (p.x < 0 || p.y < 0 || p.x >= box.width || p.y >= box.height) continue;
    if (roi.at<uchar>(p) == 0) continue;
    if (!dyn[i] && (i >= proven.size() || proven[i] == 0)) continue;
    (dyn[i] ? dyn_free : static_free).at<uchar>(p) = 0;
    ++(dyn[i] ? n_dyn : n_static);
  }
  if (n_dyn == 0 || n_static == 0) return;
  cv::Mat d_dyn, d_static;
  cv::distanceTransform(dyn_free, d_dyn, cv::DIST_L2, 3);
  cv::distanceTransform(static_free, d_static, cv::DIST_L2, 3);
  const cv::Mat remove =
      (d_static + kCarveMarginPx < d_dyn) & (d_static < static_cast<float>(radius));
  roi.setTo(0, remove);
}

}  // namespace

cv::Mat objectPixels(const cv::Mat& depth_m, const cv::Rect& box_in, double band_m,
                     double* depth_mode_m, double prior_depth_m, const cv::Mat& not_object,
                     bool prior_only, double max_depth_m) {
  if (depth_mode_m != nullptr) *depth_mode_m = 0.0;
  const cv::Rect box = box_in & cv::Rect(0, 0, depth_m.cols, depth_m.rows);
  if (box.width < 4 || box.height < 4) return {};
  const cv::Rect inner(box.width / 4, box.height * 15 / 100, std::max(1, box.width / 2),
                       std::max(1, box.height * 70 / 100));  // in the box
  const cv::Mat z = depth_m(box);
  const bool cut = !not_object.empty() || max_depth_m > 0.0;
  // Not the object's (read as depth 0 below): its pixels on a support plane, and, farther than
  // max_depth_m, where the object would be larger than it can be: that surface is behind it (the
  // wall beside a walker cut by the border, a box left on the wall). Depth compared as float.
  // (A mask, where copying the depth with them zeroed cost twice as much.)
  cv::Mat dropped;
  if (max_depth_m > 0.0) dropped = z > static_cast<float>(max_depth_m);
  if (!not_object.empty()) {
    const cv::Mat off = not_object(box) != 0;
    dropped = dropped.empty() ? off : (dropped | off);
  }
  const cv::Mat dropped_inner = dropped.empty() ? cv::Mat() : dropped(inner);
  double mode = prior_depth_m > 0.0 ? depthMode(z(inner), prior_depth_m, dropped_inner) : 0.0;
  if (mode <= 0.0) {
    mode = depthMode(z(inner), 0.0, dropped_inner);
    // Depth, but none near the prior: with prior_only the object has left the box.
    if (mode > 0.0 && prior_only && prior_depth_m > 0.0)
      return cv::Mat::zeros(depth_m.size(), CV_8UC1);
  }
  if (mode <= 0.0) {
    const bool has_depth = cut && depthMode(z(inner), 0.0) > 0.0;
    return has_depth ? cv::Mat::zeros(depth_m.size(), CV_8UC1) : cv::Mat();
  }
  if (depth_mode_m != nullptr) *depth_mode_m = mode;
  const auto lo = static_cast<float>(mode - band_m), hi = static_cast<float>(mode + band_m);
  // Depth within the band, compared as float, in one pass; a dropped pixel is selected as depth
  // 0 would be.
  const uchar dropped_sel = (0.f > lo && 0.f < hi) ? 255 : 0;
  cv::Mat sel(z.size(), CV_8UC1);
  for (int y = 0; y < z.rows; ++y) {
    const float* z_row = z.ptr<float>(y);
    const uchar* dropped_row = dropped.empty() ? nullptr : dropped.ptr<uchar>(y);
    uchar* sel_row = sel.ptr<uchar>(y);
    for (int x = 0; x < z.cols; ++x) {
      sel_row[x] = (dropped_row != nullptr && dropped_row[x] != 0) ? dropped_sel
                   : (z_row[x] > lo && z_row[x] < hi)              ? 255
                                                                   : 0;
    }
  }
  cv::morphologyEx(sel, sel, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));
  if (!not_object.empty()) sel.setTo(0, not_object(box));
  cv::Mat labels;
  const int n = cv::connectedComponents(sel, labels, 8, CV_32S);
  std::vector<int> votes(n, 0);
  for (int y = inner.y; y < inner.br().y; ++y) {  // a row's labels come in runs
    const int* label = labels.ptr<int>(y);
    for (int x = inner.x; x < inner.br().x;) {
      const int l = label[x];
      const int start = x;
      while (x < inner.br().x && label[x] == l) ++x;
      votes[l] += x - start;
    }
  }
  votes[0] = 0;
  const int best = static_cast<int>(std::max_element(votes.begin(), votes.end()) - votes.begin());
  cv::Mat out = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  if (best > 0) {
    cv::Mat in_box = out(box);
    cv::compare(labels, best, in_box, cv::CMP_EQ);
  }
  return out;
}

RegionFusion::RegionFusion(const DynamicConfig& config, const ClassTable& classes)
    : config_(config), classes_(classes) {}

ObjectTrack RegionFusion::decideObject(ObjectDecision& d, const ObjectTrack* prev,
                                       const FusionEvidence& ev) const {
  // Evidence: class prior x share of dynamic points on the object's own pixels.
  const bool observed = ev.flags_valid && d.points >= config_.min_object_points;
  const double evidence = observed ? d.weight * d.dynamic_points / d.points : 0.0;
  d.moving_now = observed && d.dynamic_points >= config_.min_dynamic_points &&
                 evidence >= config_.moving_ratio;
  // Its own points followed over time, against the pose from landmarks proven static: within
  // the pose noise (still), clearly off (moved: twice that), or in between (no verdict).
  // The pose noise in pixels, or a still person's postural sway (static_anchor_m) seen at its
  // depth, whichever is larger.
  const double sway_px =
      d.depth_m > 0.0 && ev.K[0] > 0.0 ? config_.static_anchor_m * ev.K[0] / d.depth_m : 0.0;
  const double tau =
      config_.static_anchor_px > 0.0 ? std::max(config_.static_anchor_px, sway_px) : 0.0;
  const bool anchored = tau > 0.0 && d.anchor.points >= kAnchorMinPoints;
  const double tau_z = config_.static_anchor_depth_m, dz = std::abs(d.anchor.median_dz_m);
  const bool anchor_still = anchored && d.anchor.median_px <= tau && dz <= tau_z;
  const bool anchors_off = anchored && (d.anchor.median_px > 2.0 * tau || dz > 2.0 * tau_z);
  // A person confirmed still whose anchors jump from within the still limit to beyond twice it in
  // one frame (a pose error there, or the semi-synthetic sequences' ground-truth jitter) is
  // masked in it (held, as for a flag storm, if he was kept in the frame before); his still
  // count and his anchors restart only when the next frame sees them off again.
  const bool counted_still = prev != nullptr && prev->quiet_frames >= config_.static_confirm_frames;
  const bool anchor_moved = anchors_off && !(config_.static_anchor_move_frames > 1 &&
                                             counted_still && prev->anchors_still);
  const bool confirmed_before = counted_still && !prev->moving;
  // Flags the anchors do not confirm were measured against a wrong camera motion: they mask
  // the object in this frame (below) but restart neither its quiet count nor its anchors.
  const bool flagged_now = d.moving_now;
  if (anchored && !anchor_moved) d.moving_now = false;
  const bool quiet = observed && d.points >= kStaticMinPoints &&
                     d.dynamic_points <= config_.static_max_dynamic_share * d.points;
  ObjectTrack t;
  t.box = d.detection.box;
  t.depth_m = d.depth_m > 0.0 || prev == nullptr ? d.depth_m : prev->depth_m;
  t.anchors_still = anchor_still;
  t.class_id = d.detection.class_id;
  // A depth cut that jumped is another surface (the track went to another object): it starts
  // with no slow moves.
  const bool jumped = prev != nullptr && d.depth_m > 0.0 && prev->depth_m > 0.0 &&
                      std::abs(d.depth_m - prev->depth_m) >= config_.depth_band_m;
  t.slow_moves = (prev != nullptr && !jumped ? prev->slow_moves : 0) +
                 (anchor_moved && !flagged_now && !jumped ? 1 : 0);
  const double a = config_.evidence_smoothing;
  t.score = evidence;
  if (prev != nullptr) t.score = observed ? a * prev->score + (1.0 - a) * evidence : prev->score;
  // Temporal hysteresis: the smoothed evidence must reach moving_ratio (with enough dynamic
  // points now) to turn the object moving; it stays moving until it falls below half of it.
  // Clear static evidence counts twice (a faster release). Unobserved frames keep the state.
  const bool was_moving = prev != nullptr && prev->moving;
  t.moving = was_moving ? t.score >= 0.5 * config_.moving_ratio
                        : (d.moving_now && t.score >= config_.moving_ratio);
  if (prev != nullptr && quiet) {
    t.score = a * t.score + (1.0 - a) * evidence;
    t.moving = was_moving && t.score >= 0.5 * config_.moving_ratio;
  }
  // Keeping a person takes evidence gathered over time, measured against a camera motion
  // fitted without it; one frame of clear motion removes it again.
  int before = prev != nullptr ? prev->quiet_frames : 0;
  if (prev != nullptr && prev->has_anchor) t.has_anchor = true, t.anchor_W = prev->anchor_W;
  bool still = false;  // its world position stayed put (camera pose from proven landmarks)
  t.anchors = d.anchor.kept;
  if (anchored) {
    // Its own points, followed over time, tell better than its centroid.
    still = anchor_still;
    if (anchor_moved) {
      t.anchors = d.anchor.fresh, before = 0;
      t.has_anchor = d.has_position, t.anchor_W = d.p_W;
    }
  } else if (d.has_position && config_.static_max_drift_m > 0.0) {
    // Frame-to-frame checks cannot see a slow walker (a pixel a frame): its world position can.
    if (!t.has_anchor || cv::norm(d.p_W - t.anchor_W) > config_.static_max_drift_m) {
      t.has_anchor = true, t.anchor_W = d.p_W, before = 0;
    } else {
      still = true;
    }
  }
  // Static evidence of this frame: its points agree with the background's motion, or, when it
  // has too few points to tell (a plain jacket, the depth-less border), its world position.
  const bool few_points = d.points < kStaticMinPoints;
  const bool evidence_now =
      anchored ? anchor_still : (quiet && ev.background_fit) || (few_points && still);
  t.quiet_frames = d.moving_now ? 0 : before + (evidence_now ? 1 : 0);
  if (d.moving_now) t.has_anchor = false, t.anchors = d.anchor.fresh;
  // A person confirmed still whose flags its anchors do not confirm (they drifted, but less than
  // twice the pose noise) is masked now but held: hindsight may keep him in the map.
  const bool unconfirmed_flags = confirmed_before && anchored && !anchor_moved;
  d.motion_now = (flagged_now && !unconfirmed_flags) || anchor_moved || t.moving;
  if (classes_.isHighDynamic(d.detection.class_id)) {
    // Anchors off by more than the pose noise mask it in this frame (its count is kept).
    const int needed = config_.static_confirm_frames << std::min(t.slow_moves, kMaxSlowDoublings);
    const bool evidenced = t.moving || (anchored && !anchor_still);
    t.moving = evidenced || t.quiet_frames < needed;
    d.unconfirmed = t.moving && !evidenced && !flagged_now && t.slow_moves == 0 &&
                    t.score < config_.moving_ratio;
  }
  d.moving = t.moving;
  d.quiet_frames = t.quiet_frames;
  return t;
}

void RegionFusion::propagateTracks(const std::vector<cv::Point2f>& points,
                                   const FusionEvidence& evidence) {
  if (evidence.prev_points.size() != points.size()) return;
  for (auto& t : tracks_) {
    cv::Point2f flow;
    if (medianFlowIn(t.box, evidence.prev_points, points, &flow)) t.box += flow;
  }
}

cv::Mat RegionFusion::objectRegion(const cv::Mat& depth_m, const cv::Rect& box, ObjectDecision& d,
                                   const std::vector<cv::Point2f>& points,
                                   const std::vector<std::uint8_t>& dyn,
                                   const ObjectTrack* prev) const {
  const double prior = prev != nullptr ? prev->depth_m : 0.0;
  // A carried box at the image border may have lost its object through the border: then it is
  // the object only at the object's own depth, not at whatever its centre shows now.
  const bool at_border =
      box.x <= 0 || box.y <= 0 || box.br().x >= depth_m.cols || box.br().y >= depth_m.rows;
  const bool prior_only = d.carried && at_border && config_.carried_border_exit;
  // A person is no taller than person_max_height_m: a box h pixels tall holds one no farther
  // than that height seen over h pixels (the box may be cut by the border: then nearer still).
  static const int kPerson = ClassTable::classIndex("person");
  const double fy = evidence_->K[1];
  const double max_depth =
      d.detection.class_id == kPerson && config_.person_max_height_m > 0.0 && fy > 0.0
          ? config_.person_max_height_m * fy / box.height
          : 0.0;
  cv::Mat region = objectPixels(depth_m, box, config_.depth_band_m, &d.depth_m, prior,
                                evidence_->planes, prior_only, max_depth);
  if (region.empty()) {
    region = cv::Mat::zeros(depth_m.size(), CV_8UC1);
    region(box).setTo(255);
  }
  if (evidence_->has_pose && d.depth_m > 0.0) {
    // The region's centroid in the box (cv::moments' m00, m10, m01 of the binary region: sums
    // of whole numbers, exact in either form; the other seven moments are not needed).
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
    if (m00 > 0) {
      const double u = box.x + static_cast<double>(m10) / static_cast<double>(m00);
      const double v = box.y + static_cast<double>(m01) / static_cast<double>(m00), z = d.depth_m;
      const cv::Vec4d& K = evidence_->K;
      const cv::Vec4d p_C((u - K[2]) / K[0] * z, (v - K[3]) / K[1] * z, z, 1.0);
      const cv::Vec4d p_W = evidence_->T_W_C * p_C;
      d.p_W = cv::Vec3d(p_W[0], p_W[1], p_W[2]);
      d.has_position = true;
    }
  }
  const bool with_ids = evidence_->has_pose && evidence_->point_ids.size() == points.size();
  std::vector<PointSample> samples;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!inside(region, points[i])) continue;
    ++d.points;
    if (dyn[i]) ++d.dynamic_points;
    if (with_ids) {
      samples.push_back({evidence_->point_ids[i], points[i],
                         windowInteriorDepth(depth_m, cvRound(points[i].x), cvRound(points[i].y),
                                             kAnchorWindowPx, kAnchorWindowM)});
    }
  }
  if (with_ids) {
    static const std::vector<PointAnchor> kNone;
    d.anchor = checkAnchors(prev != nullptr ? prev->anchors : kNone, samples, evidence_->T_W_C,
                            evidence_->K);
  }
  return region;
}

std::vector<std::uint64_t> RegionFusion::idsIn(const cv::Mat& region,
                                               const std::vector<cv::Point2f>& points) const {
  std::vector<std::uint64_t> ids;
  if (evidence_->point_ids.size() != points.size()) return ids;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (inside(region, points[i])) ids.push_back(evidence_->point_ids[i]);
  }
  return ids;
}

void RegionFusion::applyObject(FusionMode mode, ObjectDecision& d, cv::Mat& region,
                               const cv::Rect& box, const std::vector<cv::Point2f>& points,
                               const std::vector<std::uint8_t>& dyn, FusionResult& result) const {
  if (d.moving && mode == FusionMode::kBoth) {
    carveStatic(region, box, points, dyn, proven_, config_.static_carve_radius_px);
  }
  // The region lies in its box: only the box of each mask is touched.
  const cv::Mat in_box = region(box);
  const auto add = [&](const cv::Mat& mask) {  // writes into mask's pixels
    cv::Mat roi = mask(box);
    roi |= in_box;
  };
  add(d.moving ? result.mask : result.static_objects);
  if (d.moving) add(d.unconfirmed ? result.unconfirmed : certain_);
  if (d.moving) add(d.motion_now || mode != FusionMode::kBoth ? evidenced_ : result.held);
  if (!d.moving && d.quiet_frames >= config_.static_confirm_frames) add(confirmed_);
  result.objects.push_back(d);
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

FusionResult RegionFusion::fuse(FusionMode mode, const cv::Mat& depth_m,
                                const std::vector<cv::Point2f>& points,
                                const std::vector<std::uint8_t>& dyn,
                                const std::vector<Detection>& all_detections,
                                const FusionEvidence& evidence) {
  // A teddy bear that is also a 0.3 "person" is one object: the better-scored class wins.
  const std::vector<Detection> detections = oneLabelPerObject(all_detections);
  FusionResult result;
  proven_ = evidence.proven_static;
  evidence_ = &evidence;
  confirmed_ = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  certain_ = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  evidenced_ = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  result.unconfirmed = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  result.held = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  result.mask = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  result.static_objects = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  cv::Mat claimed = cv::Mat::zeros(depth_m.size(), CV_8UC1);  // pixels of detected objects
  std::vector<ObjectTrack> next;
  if (mode != FusionMode::kGeometry) {
    propagateTracks(points, evidence);
    const std::vector<int> track_of = associateDetections(detections, tracks_, kMatchIou);
    std::vector<bool> matched(tracks_.size(), false);
    for (std::size_t k = 0; k < detections.size(); ++k) {
      ObjectDecision d = newDecision(detections[k]);
      if (d.weight <= 0.0) continue;
      if (mode == FusionMode::kDetector && !classes_.isHighDynamic(d.detection.class_id)) continue;
      const cv::Rect box = clampRect(d.detection.box, depth_m.size());
      if (box.area() <= 0) continue;
      int track = track_of[k];
      const ObjectTrack* prev = track >= 0 ? &tracks_[track] : nullptr;
      cv::Mat region = objectRegion(depth_m, box, d, points, dyn, prev);
      if (prev == nullptr && mode == FusionMode::kBoth) {
        // No box overlaps it enough; the points on it may still be an earlier track's.
        track = trackSharingPoints(idsIn(region, points), tracks_, d.detection.class_id,
                                   kAnchorMinPoints);
        if (track >= 0) {
          prev = &tracks_[track];
          d = newDecision(detections[k]);
          region = objectRegion(depth_m, box, d, points, dyn, prev);
        }
      }
      if (mode == FusionMode::kDetector) {
        d.moving_now = d.moving = true;
      } else {
        if (prev != nullptr) matched[track] = true;
        next.push_back(decideObject(d, prev, evidence));
      }
      claimed(box) |= region(box);
      applyObject(mode, d, region, box, points, dyn, result);
    }
    // Objects the detector did not report in this frame: a person seen a moment ago keeps its
    // mask (and its evidence) for a few frames, its box moved with the flow.
    for (std::size_t t = 0; t < tracks_.size() && mode == FusionMode::kBoth; ++t) {
      const ObjectTrack& track = tracks_[t];
      const cv::Rect box = clampRect(track.box, depth_m.size());
      if (matched[t] || track.missed >= config_.track_max_missed_frames ||
          box.area() * 4 < track.box.area()) {
        continue;
      }
      ObjectDecision d = newDecision(Detection{track.box, track.class_id, 0.f});
      d.carried = true;
      cv::Mat region = objectRegion(depth_m, box, d, points, dyn, &track);
      next.push_back(decideObject(d, &track, evidence));
      next.back().missed = track.missed + 1;
      claimed(box) |= region(box);
      applyObject(mode, d, region, box, points, dyn, result);
    }
  }
  tracks_ = std::move(next);
  // What has proven static over time is not another object's: a walker's box that covers the
  // teddy (or a standing person) must not take its depth cut.
  if (cv::countNonZero(confirmed_) > 0) result.mask.setTo(0, confirmed_);
  if (mode != FusionMode::kDetector && evidence.flags_valid) {
    cv::Mat grown = cv::Mat::zeros(depth_m.size(), CV_8UC1);
    result.clusters = growClusters(depth_m, points, dyn, claimed, grown);
    result.mask |= grown;
    certain_ |= grown;
    evidenced_ |= grown;
  }
  result.unconfirmed.setTo(0, certain_ | confirmed_);
  result.confirmed = confirmed_;
  if (config_.mask_dilation_px > 0 && cv::countNonZero(result.mask) > 0) {
    const int k = 2 * config_.mask_dilation_px + 1;
    const cv::Mat disc = cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k});
    cv::dilate(result.mask, result.mask, disc);
    // The held margin is the held object's, but not where a moving object's margin reaches.
    cv::dilate(result.held, result.held, disc);
    cv::dilate(evidenced_, evidenced_, disc);
  }
  result.held.setTo(0, evidenced_ | confirmed_);
  return result;
}

bool RegionFusion::inPlaceEarlier(const cv::Mat& depth_m, const cv::Mat& region,
                                  const cv::Rect& roi) const {
  const double share = config_.cluster_max_consistent;
  if (share <= 0.0 || evidence_->view == nullptr || !evidence_->has_pose) return false;
  const DepthAgreement a = compareWithView(depth_m, region, roi, evidence_->T_W_C, evidence_->K,
                                           *evidence_->view, DepthCheckOptions());
  return a.samples >= kInPlaceMinSamples && a.share(a.consistent) >= share;
}

int RegionFusion::growClusters(const cv::Mat& depth_m, const std::vector<cv::Point2f>& points,
                               const std::vector<std::uint8_t>& dyn, const cv::Mat& claimed,
                               cv::Mat& mask) const {
  std::vector<int> free_dyn;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (dyn[i] && !inside(claimed, points[i])) free_dyn.push_back(static_cast<int>(i));
  }
  int grown = 0;
  for (const auto& group : clusterPoints(points, free_dyn, config_.cluster_radius_px)) {
    if (static_cast<int>(group.size()) < config_.min_cluster_points) continue;
    std::vector<cv::Point2f> gp;
    for (int i : group) gp.push_back(points[i]);
    const cv::Rect tight = cv::boundingRect(gp);
    // Support: most tracked points around the cluster must be dynamic, else it is noise.
    const cv::Rect near = cv::Rect(tight.x - 10, tight.y - 10, tight.width + 20, tight.height + 20);
    int all = 0;
    for (const auto& p : points) all += near.contains(cv::Point(cvRound(p.x), cvRound(p.y)));
    if (2 * static_cast<int>(group.size()) < all) continue;
    const double m = config_.cluster_box_margin;
    const cv::Point2f c(tight.x + 0.5f * tight.width, tight.y + 0.5f * tight.height);
    const float hw = static_cast<float>(std::max(40.0, m * tight.width) / 2);
    const float hh = static_cast<float>(std::max(40.0, m * tight.height) / 2);
    const cv::Rect roi = clampRect(cv::Rect2f(c.x - hw, c.y - hh, 2 * hw, 2 * hh), depth_m.size());
    cv::Mat flood = cv::Mat::zeros(roi.height + 2, roi.width + 2, CV_8UC1);
    flood(cv::Rect(1, 1, roi.width, roi.height)).setTo(1, claimed(roi));  // never grow into objects
    if (!evidence_->planes.empty())
      flood(cv::Rect(1, 1, roi.width, roi.height)).setTo(1, evidence_->planes(roi));
    const cv::Mat depth_roi = depth_m(roi).clone();
    const double step = config_.flood_depth_step_m;
    for (int i : group) {
      const cv::Point s(cvRound(points[i].x) - roi.x, cvRound(points[i].y) - roi.y);
      if (!cv::Rect(0, 0, roi.width, roi.height).contains(s)) continue;
      if (depth_roi.at<float>(s) <= 0.f || flood.at<uchar>(s.y + 1, s.x + 1) != 0) continue;
      cv::floodFill(depth_roi, flood, s, cv::Scalar(), nullptr, cv::Scalar(step), cv::Scalar(step),
                    8 | cv::FLOODFILL_MASK_ONLY | (255 << 8));
    }
    cv::Mat filled = cv::Mat::zeros(depth_m.size(), CV_8UC1);
    filled(roi).setTo(255, flood(cv::Rect(1, 1, roi.width, roi.height)) == 255);
    carveStatic(filled, roi, points, dyn, proven_, config_.static_carve_radius_px);
    if (inPlaceEarlier(depth_m, filled, roi)) continue;
    filled = filled(roi);
    if (cv::countNonZero(filled) == 0) {  // no depth: the hull of the points
      std::vector<cv::Point> hull;
      for (const auto& p : gp) hull.emplace_back(cvRound(p.x), cvRound(p.y));
      cv::convexHull(std::vector<cv::Point>(hull), hull);
      cv::fillConvexPoly(mask, hull, 255);
    } else {
      mask(roi) |= filled;
    }
    ++grown;
  }
  return grown;
}

}  // namespace dynamap
