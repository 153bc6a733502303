#include "dynamap/core/dynamic/dynamic_motion_filter.hpp"

#include "dynamap/core/dynamic/detector_worker.hpp"
#include "dynamap/core/dynamic/mover_regions.hpp"
#include "dynamap/core/dynamic/support_planes.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

namespace dynamap {

namespace {

using Clock = std::chrono::steady_clock;

/// addMovers(): the view's age in the first frames, before there is an older one.
constexpr long kStartupFramesBack = 3;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

FusionMode parseMode(const std::string& mode) {
  if (mode == "geometry") return FusionMode::kGeometry;
  if (mode == "detector") return FusionMode::kDetector;
  if (mode == "both") return FusionMode::kBoth;
  throw std::invalid_argument("dynamic.mode: '" + mode +
                              "' (known: off, geometry, detector, both)");
}

bool inMask(const cv::Mat& mask, const cv::Point2f& p) {
  const int x = cvRound(p.x), y = cvRound(p.y);
  return !mask.empty() && x >= 0 && y >= 0 && x < mask.cols && y < mask.rows &&
         mask.at<uchar>(y, x) != 0;
}

/// The tracker's camera motion as checkRigidMotion() writes motions: X_prev = R X_cur + t
/// (valid false without a prior).
RigidMotion priorMotion(const MotionFilterInput& input) {
  RigidMotion prior;
  if (!input.has_prior) return prior;
  const Eigen::Matrix3d R = input.T_prev_cur.rotation();
  const cv::Matx33d Rm(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1),
                       R(2, 2));
  cv::Rodrigues(Rm, prior.rvec);
  const Eigen::Vector3d t = input.T_prev_cur.translation();
  prior.tvec = cv::Vec3d(t.x(), t.y(), t.z());
  prior.valid = true;
  return prior;
}

/// `mask` if any of its pixels is set, else an empty Mat (what MotionFilterOutput's masks say).
cv::Mat anyOrEmpty(const cv::Mat& mask) {
  return !mask.empty() && cv::countNonZero(mask) > 0 ? mask : cv::Mat();
}

/// Per match: dynamic (flagged, or on the mask) and held back; the masks of `fused`.
MotionFilterOutput filterOutput(const std::vector<cv::Point2f>& cur_px,
                                const std::vector<std::uint8_t>& flagged,
                                const FusionResult& fused) {
  MotionFilterOutput out;
  out.match_is_dynamic.resize(cur_px.size(), 0);
  for (std::size_t i = 0; i < cur_px.size(); ++i) {
    // A lone flag on an object decided static (e.g. the teddy taken for a person, whose near
    // points have larger residuals) is noise: the object-level decision wins.
    const bool lone_flag = flagged[i] && !inMask(fused.static_objects, cur_px[i]);
    out.match_is_dynamic[i] = (lone_flag || inMask(fused.mask, cur_px[i])) ? 1 : 0;
  }
  out.match_held.assign(cur_px.size(), 0);
  for (std::size_t i = 0; i < cur_px.size() && !fused.unconfirmed.empty(); ++i) {
    out.match_held[i] = !flagged[i] && inMask(fused.unconfirmed, cur_px[i]) ? 1 : 0;
  }
  out.unconfirmed_mask = fused.unconfirmed;
  out.held_mask = anyOrEmpty(fused.held);
  out.confirmed_mask = anyOrEmpty(fused.confirmed);
  out.moved_object_mask = anyOrEmpty(fused.moved_objects);
  out.dynamic_mask = anyOrEmpty(fused.mask);
  return out;
}

SupportPlaneOptions supportPlaneOptions(const DynamicConfig& c) {
  SupportPlaneOptions o;
  o.max_planes = c.support_planes;
  return o;
}

SeenThroughOptions seenThroughOptions(const DynamicConfig& c) {
  SeenThroughOptions o;
  o.min_region_px = c.dense_min_region_px;
  o.depth_range_m = c.dense_depth_range_m;
  o.grow_m = c.dense_grow_m;
  o.barrier_step_m = c.dense_barrier_step_m;
  return o;
}

}  // namespace

DetectorOptions detectorOptions(const DynamicConfig& c) {
  DetectorOptions o;
  o.kind = c.detector;
  o.model_cfg = c.model_cfg;
  o.model_weights = c.model_weights;
  o.input_width = c.input_width;
  o.input_height = c.input_height;
  if (c.nms != "plain" && c.nms != "recall") {
    throw std::invalid_argument("dynamic.nms: '" + c.nms + "' (known: plain, recall)");
  }
  o.nms.kind = c.nms == "plain" ? NmsKind::kPlain : NmsKind::kRecall;
  o.nms.iou_threshold = static_cast<float>(c.nms_iou_threshold);
  o.nms.score_threshold = static_cast<float>(c.score_threshold);
  o.nms.soft_sigma = static_cast<float>(c.soft_nms_sigma);
  o.nms.dedup_iou = static_cast<float>(c.nms_dedup_iou);
  return o;
}

DynamicMotionFilter::DynamicMotionFilter(const DynamicConfig& config, const PinholeCamera& camera,
                                         TimingRecorder* timing)
    : config_(config),
      K_(camera.fx, camera.fy, camera.cx, camera.cy),
      mode_(parseMode(config.mode)),
      classes_(config),
      fusion_(config, classes_),
      timing_(timing),
      depth_history_(std::max(2 * config.dense_check_frames, config.mover_view_frames)) {
  if (mode_ != FusionMode::kGeometry && config.detector != "none") {
    worker_ = std::make_unique<DetectorWorker>(
        makeObjectDetector(detectorOptions(config), classes_), config.detector_threads,
        [this](double ms) { record("detector", ms); });
  }
}

// The detector thread records its timings into own_timing_, declared after worker_: members die
// in reverse order, so without this a detection still in flight wrote into a destroyed recorder
// (AddressSanitizer, heap-use-after-free, TeddyDynDev.FusionMasksWalkers...).
DynamicMotionFilter::~DynamicMotionFilter() { worker_.reset(); }

void DynamicMotionFilter::record(const std::string& stage, double ms) {
  own_timing_.add(stage, ms);
  if (timing_ != nullptr) timing_->add(stage, ms);
}

void DynamicMotionFilter::beginFrame(const RgbdFrame& frame) {
  ++frame_no_;
  begun_stamp_ = frame.timestamp_s;
  if (!worker_ || frame.bgr.empty()) return;
  if (lockstep()) takeDetections(true);  // the previous frame's, whatever the threads' timing
  if (lockstep() && !detectedFrame(frame_no_)) return;
  const bool wait = !config_.detector_async || lockstep();
  if (!worker_->submit(frame.bgr, frame_no_, frame.timestamp_s, wait)) {
    record("detector_skipped", 0.0);
  }
}

void DynamicMotionFilter::prefetch(const RgbdFrame& next) {
  // Only lockstep runs read ahead: there the frame after this one is always begun next.
  // With detector_every_frames > 1 it would have to know the next frame's number, which the
  // reader's thread does not: no read-ahead then (the detector still overlaps the tracking of
  // the frame it was given).
  if (!worker_ || !lockstep() || next.bgr.empty() || config_.detector_every_frames > 1) return;
  worker_->prefetch(next.bgr, next.timestamp_s);
}

bool DynamicMotionFilter::detectedFrame(long frame_no) const {
  return frame_no % std::max(1, config_.detector_every_frames) == 0;
}

bool DynamicMotionFilter::lockstep() const {
  return config_.detector_async && config_.detector_lockstep;
}

void DynamicMotionFilter::takeDetections(bool wait) {
  const auto start = Clock::now();
  DetectorWorker::Result result;
  if (worker_->take(&result, wait)) {
    latest_.detections = std::move(result.detections);
    latest_.frame_no = result.frame_no;
    latest_.stamp = result.stamp;
    record("detector_fresh", 0.0);
  }
  record("detector_wait", msSince(start));
}

std::vector<Detection> DynamicMotionFilter::currentDetections(const RgbdFrame* frame,
                                                              const FeatureMatches& m) {
  if (!worker_ || frame == nullptr || frame->bgr.empty()) return {};
  const bool begun = frame_no_ >= 0 && frame->timestamp_s == begun_stamp_;
  const bool sync = !config_.detector_async;
  // The very first frame has no earlier detections to use: it waits for its own, so that the
  // first keyframe (the map's start) never takes a person for background.
  const bool first = begun && latest_.frame_no < 0;
  if (!lockstep() || first) takeDetections(sync || first);  // lockstep: beginFrame() took them
  if (sync) {  // the frame's own detections (beginFrame() not called for it: detect now)
    if (begun && latest_.frame_no == frame_no_) return latest_.detections;
    return worker_->runNow(frame->bgr);
  }
  const long age = frame_no_ - latest_.frame_no;
  if (latest_.frame_no < 0 || !begun || age > config_.detector_max_age_frames) return {};
  record("detector_age", 1000.0 * (frame->timestamp_s - latest_.stamp));
  // Older detections: each box moves with the median flow of the matches inside it (a walker
  // close to the camera moves tens of pixels a frame) and grows a little per frame of age;
  // fusion cuts them by depth again.
  std::vector<Detection> dets = latest_.detections;
  const auto grow = static_cast<float>(config_.stale_box_growth_px * static_cast<double>(age));
  for (auto& d : dets) {
    cv::Point2f flow;
    if (age > 0 && medianFlowIn(d.box, m.prev_px, m.cur_px, &flow)) {
      d.box += flow * static_cast<float>(age);
    }
    d.box =
        cv::Rect2f(d.box.x - grow, d.box.y - grow, d.box.width + 2 * grow, d.box.height + 2 * grow);
  }
  return dets;
}

EpipolarResult DynamicMotionFilter::checkGeometry(const FeatureMatches& m, const cv::Mat& depth,
                                                  const std::vector<Detection>& dets,
                                                  const RigidMotion* prior, bool* background_fit) {
  *background_fit = false;
  EpipolarOptions eo;
  eo.threshold_px = config_.epipolar_threshold_px;
  eo.min_matches = config_.min_matches;
  eo.min_parallax_px = config_.min_parallax_px;
  eo.confidence = config_.ransac_confidence;
  eo.homography_inlier_ratio = config_.homography_inlier_ratio;
  eo.reprojection_threshold_px = config_.reprojection_threshold_px;
  eo.rigid_epipolar_threshold_px = config_.rigid_epipolar_threshold_px;
  eo.bucket_px = config_.bucket_px;
  eo.ransac_iterations = config_.ransac_iterations;
  // Matches on last frame's moving regions and inside high-dynamic boxes count less (by default
  // nothing) when voting for the camera motion: people who fill the frame would otherwise make
  // the camera follow them, and then the check measures nothing. A wrong mask cannot lock
  // itself in: an object's points are still checked against the background's motion, and
  // fusion keeps an object that stays still there.
  const std::size_t n = m.cur_px.size();
  std::vector<float> weight(n, 1.f);
  int background = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (inMask(prev_mask_, m.cur_px[i])) weight[i] *= static_cast<float>(config_.masked_fit_weight);
    for (const auto& d : dets) {
      if (classes_.isHighDynamic(d.class_id) && d.box.contains(m.cur_px[i])) {
        weight[i] *= static_cast<float>(config_.boxed_fit_weight);
        break;
      }
    }
    background += weight[i] == 1.f ? 1 : 0;
  }
  if (config_.geometric_check == "epipolar" || depth.empty()) {
    // The paper's check: fundamental matrix (or homography at low parallax) of the background.
    std::vector<std::uint8_t> subset(n);
    for (std::size_t i = 0; i < n; ++i) subset[i] = weight[i] == 1.f ? 1 : 0;
    EpipolarResult r = checkEpipolar(m.prev_px, m.cur_px, eo, subset);
    *background_fit = r.model != EpipolarModel::kNone;
    return r;
  }
  EpipolarResult r = checkRigidMotion(m.prev_px, m.cur_px, depth, K_, weight, eo, &motion_, prior);
  *background_fit =
      r.model == EpipolarModel::kRigid && (r.from_prior || background >= config_.min_matches);
  return r;
}

void DynamicMotionFilter::keepLastDepth(const MotionFilterInput& input) {
  if (pending_.frame != filtered_ - 1) return;
  // The last frame's final pose: X_W = T_W_C T_prev_cur^-1 X_prev.
  cv::eigen2cv(Eigen::Matrix4d((input.T_W_C * input.T_prev_cur.inverse()).matrix()),
               pending_.T_W_C);
  if (config_.views_follow_pose_snaps && pending_prior_)
    depth_history_.followPoseSnap(pending_.T_W_C, *pending_prior_);
  depth_history_.push(std::move(pending_));
}

void DynamicMotionFilter::addSeenThrough(const cv::Mat& depth_m, const FusionEvidence& evidence,
                                         FusionResult& fused) {
  const DepthView* view = evidence.view;  // the same earlier view fusion's clusters were held to
  if (view == nullptr || depth_m.empty()) return;
  const SeenThroughOptions o = seenThroughOptions(config_);
  // Objects already decided (moving or kept) are fusion's: a kept person is not re-judged here.
  const auto still_planes = [&](const cv::Mat& seeds) {
    return stillPlaneCells(depth_m, evidence.T_W_C, evidence.K, *view, planes_,
                           supportPlaneOptions(config_), o.check, seeds);
  };
  cv::Mat moved =
      seenThroughRegions(depth_m, evidence.T_W_C, evidence.K, *view,
                         fused.mask | fused.static_objects, o, &fused.seen_through, still_planes);
  if (fused.seen_through == 0) return;
  if (config_.mask_dilation_px > 0) {
    const int k = 2 * config_.mask_dilation_px + 1;
    cv::dilate(moved, moved, cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k}));
  }
  fused.mask |= moved;
  if (!fused.unconfirmed.empty()) fused.unconfirmed.setTo(0, moved);
  if (!fused.held.empty()) fused.held.setTo(0, moved);
}

bool DynamicMotionFilter::moverTracks() const {
  return config_.mover_tracks && mode_ == FusionMode::kBoth;
}

void DynamicMotionFilter::addMovers(const cv::Mat& depth_m, const FusionEvidence& evidence,
                                    std::vector<Detection>& dets) {
  // The view mover_view_frames back (an older one: a slow mover has moved farther, a fast one
  // has left more of its old place), else dense_check_frames back. The first frames have no view
  // that old: one kStartupFramesBack back finds a mover in view from the first frame before it
  // has made the map.
  const DepthView* view = nullptr;
  for (const long back : {static_cast<long>(config_.mover_view_frames),
                          static_cast<long>(config_.dense_check_frames), kStartupFramesBack}) {
    if (view == nullptr && back > 0 && evidence.has_pose)
      view = depth_history_.newestUpTo(filtered_ - back);
  }
  if (!moverTracks() || view == nullptr || depth_m.empty()) return;
  const auto start = Clock::now();
  std::vector<Detection> people = dets;  // and last frame's, also those carried undetected
  people.insert(people.end(), prev_people_.begin(), prev_people_.end());
  const cv::Mat exclude = notMovers(depth_m, prev_kept_movers_, evidence.planes, people, classes_,
                                    config_.depth_band_m);
  const cv::Mat walkers = peoplePixels(depth_m, prev_walkers_, classes_, config_.depth_band_m);
  SeenThroughOptions options = seenThroughOptions(config_);
  options.check.max_depth_m = config_.mover_max_depth_m;
  const std::vector<Detection> movers = moverDetections(depth_m, evidence.T_W_C, evidence.K, *view,
                                                        exclude, options, nullptr, walkers);
  dets.insert(dets.end(), movers.begin(), movers.end());
  record("movers", msSince(start));
}

cv::Mat DynamicMotionFilter::supportPlanePixels(const cv::Mat& depth_m,
                                                const std::vector<Detection>& dets) {
  planes_.clear();
  if (config_.support_planes <= 0 || depth_m.empty() || mode_ == FusionMode::kDetector) return {};
  const auto start = Clock::now();
  cv::Mat exclude =
      prev_mask_.empty() ? cv::Mat::zeros(depth_m.size(), CV_8UC1) : prev_mask_.clone();
  for (const auto& d : dets) {
    const cv::Rect box = cv::Rect(d.box) & cv::Rect(0, 0, depth_m.cols, depth_m.rows);
    if (box.area() > 0) exclude(box).setTo(255);
  }
  const SupportPlaneOptions o = supportPlaneOptions(config_);
  planes_ = findSupportPlanes(depth_m, K_, exclude, o);
  cv::Mat on_plane = planePixels(depth_m, K_, planes_, o);
  record("support_planes", msSince(start));
  return on_plane;
}

EpipolarResult DynamicMotionFilter::flagMovingPoints(const MotionFilterInput& input,
                                                     const FeatureMatches& m,
                                                     const cv::Mat& depth_m,
                                                     const std::vector<Detection>& dets,
                                                     bool* background_fit) {
  const auto start = Clock::now();
  EpipolarResult epi;
  if (mode_ != FusionMode::kDetector) {
    const RigidMotion prior = priorMotion(input);
    epi = checkGeometry(m, depth_m, dets, prior.valid ? &prior : nullptr, background_fit);
  }
  epi.is_dynamic.resize(m.cur_px.size(), 0);
  record("epipolar", msSince(start));
  return epi;
}

void DynamicMotionFilter::gatherEvidence(const MotionFilterInput& input, const FeatureMatches& m,
                                         const EpipolarResult& epi, FusionEvidence& evidence) {
  evidence.flags_valid = mode_ == FusionMode::kDetector || epi.model != EpipolarModel::kNone;
  evidence.prev_points = m.prev_px;
  if (input.proven_static != nullptr) evidence.proven_static = *input.proven_static;
  if (m.ids.size() == m.cur_px.size()) evidence.point_ids = m.ids;
  evidence.K = K_;  // a person's size bound needs it with or without a pose
  if (input.has_prior) {
    evidence.has_pose = true;
    cv::eigen2cv(Eigen::Matrix4d(input.T_W_C.matrix()), evidence.T_W_C);
    keepLastDepth(input);
  }
  if (evidence.has_pose && config_.dense_check_frames > 0)
    evidence.view = depth_history_.newestUpTo(filtered_ - config_.dense_check_frames);
}

FusionResult DynamicMotionFilter::fuseRegions(const MotionFilterInput& input,
                                              const FeatureMatches& m, const cv::Mat& depth_m,
                                              const std::vector<Detection>& dets,
                                              const EpipolarResult& epi, FusionEvidence& evidence) {
  auto start = Clock::now();
  cv::Mat depth = depth_m;
  if (depth.empty()) {
    const cv::Size size = input.cur_gray != nullptr ? input.cur_gray->size() : cv::Size(640, 480);
    depth = cv::Mat::zeros(size, CV_32FC1);
  }
  FusionResult fused = fusion_.fuse(mode_, depth, m.cur_px, epi.is_dynamic, dets, evidence);
  record("fusion", msSince(start));
  start = Clock::now();
  // With mover tracks too: what they do not hold (people's parts in their boxes) as before.
  if (evidence.has_pose && mode_ != FusionMode::kDetector) addSeenThrough(depth_m, evidence, fused);
  record("dense_check", msSince(start));
  return fused;
}

void DynamicMotionFilter::endFrame(const MotionFilterInput& input, const cv::Mat& depth_m,
                                   const FusionResult& fused) {
  prev_mask_ = fused.mask;
  if (moverTracks()) prev_kept_movers_ = keptMovers(fused);
  prev_people_.clear();
  prev_walkers_.clear();
  for (const auto& o : fused.objects) {
    if (!moverTracks() || !classes_.isHighDynamic(o.detection.class_id) ||
        o.detection.class_id == ClassTable::kMover)
      continue;
    prev_people_.push_back(o.detection);
    if (o.moving) prev_walkers_.push_back(o.detection);
  }
  pending_ = DepthView();
  if (config_.dense_check_frames > 0) pending_ = DepthHistory::halfView(depth_m, filtered_);
  pending_prior_.reset();
  if (input.has_prior) {
    cv::Matx44d prior;
    cv::eigen2cv(Eigen::Matrix4d(input.T_W_C.matrix()), prior);
    pending_prior_ = prior;
  }
  ++filtered_;
}

void DynamicMotionFilter::keepDiagnostics(const FeatureMatches& m, const EpipolarResult& epi,
                                          const MotionFilterOutput& out,
                                          std::vector<Detection> dets, FusionResult fused) {
  diagnostics_.matches = m;
  diagnostics_.epipolar_dynamic = epi.is_dynamic;
  diagnostics_.residual_px = epi.residual_px;
  diagnostics_.match_is_dynamic = out.match_is_dynamic;
  diagnostics_.model = epi.model;
  diagnostics_.detections = std::move(dets);
  diagnostics_.objects = std::move(fused.objects);
  diagnostics_.clusters = fused.clusters;
  diagnostics_.seen_through = fused.seen_through;
  diagnostics_.mask = fused.mask;
}

// The per-frame step: detections -> geometric check of the matches -> fusion of the two.
MotionFilterOutput DynamicMotionFilter::filter(const MotionFilterInput& input) {
  static const FeatureMatches kNoMatches;
  const FeatureMatches& m = input.matches != nullptr ? *input.matches : kNoMatches;
  std::vector<Detection> dets = currentDetections(input.frame, m);
  const cv::Mat depth_m = input.frame != nullptr ? input.frame->depth_m : cv::Mat();
  FusionEvidence evidence;
  const EpipolarResult epi = flagMovingPoints(input, m, depth_m, dets, &evidence.background_fit);
  evidence.planes = supportPlanePixels(depth_m, dets);  // records its own time
  gatherEvidence(input, m, epi, evidence);
  addMovers(depth_m, evidence, dets);  // records "movers"
  FusionResult fused = fuseRegions(input, m, depth_m, dets, epi, evidence);
  MotionFilterOutput out = filterOutput(m.cur_px, epi.is_dynamic, fused);
  endFrame(input, depth_m, fused);
  keepDiagnostics(m, epi, out, std::move(dets), std::move(fused));
  return out;
}

std::unique_ptr<MotionFilter> makeMotionFilter(const DynamicConfig& config,
                                               const PinholeCamera& camera,
                                               TimingRecorder* timing) {
  if (config.mode == "off") return nullptr;
  return std::make_unique<DynamicMotionFilter>(config, camera, timing);
}

}  // namespace dynamap
