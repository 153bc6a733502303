// MappingWorker's online judgement window (see the class comment in mapping_worker.hpp): each
// keyframe is judged by the held revision and the visibility votes against the keyframes near it
// in time, then integrated. Everything here runs on the thread that holds backend_mutex_.
#include <algorithm>

#include "dynamap/mapping/mapping_worker.hpp"

namespace dynamap {
namespace {

constexpr double kRevisitReachM = 0.5;  // a kept view judges keyframes this near...
constexpr double kRevisitReachRad = 30.0 * 3.14159265358979 / 180.0;  // ... and turned
constexpr double kRevisitSpacingM = 0.1;  // a view is kept where no kept one is this near...
constexpr double kRevisitSpacingRad = 10.0 * 3.14159265358979 / 180.0;  // ... and turned

double angleRad(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.rotation().transpose() * b.rotation()).angle();
}

}  // namespace

void MappingWorker::judgeReadyLocked(bool flush) {
  if (judge_.empty()) return;
  const bool judging = options_.visibility.enabled || options_.held_revision_voxel_m > 0.0;
  const double after_s = judging ? options_.window_after_s : 0.0;
  const double newest_s = records_.at(judge_.back()).timestamp_s;
  std::size_t end = judged_;  // targets: [judged_, end), once the oldest waited a batch more
  const bool due =
      judged_ < judge_.size() && records_.at(judge_[judged_]).timestamp_s <=
                                     newest_s - after_s - (judging ? options_.window_batch_s : 0.0);
  while ((flush || due) && end < judge_.size() &&
         (flush || records_.at(judge_[end]).timestamp_s <= newest_s - after_s)) {
    ++end;
  }
  if (end > judged_ || flush) {
    ScopedStageTimer timer(timings_, "mapping_judge");
    reviseHeldWindowLocked(judged_, end, flush);
    if (end > judged_) removeSeenThroughWindowLocked(judged_, end);
  }
  for (std::size_t i = judged_; i < end; ++i) {
    KeyframeRecord& rec = records_.at(judge_[i]);
    if (waitsForStartupLook(rec)) {
      rec.startup_wait = true;
      startup_waiting_.push_back(judge_[i]);
    } else {
      integrateRecordLocked(judge_[i]);
    }
  }
  judged_ = end;
  judgeStartupLocked(flush);
  // Context older than window_before_s before the next keyframe to judge (or the last judged)
  // leaves the window: its view and confirmed points are released.
  const std::size_t next = std::min(judged_, judge_.size() - 1);
  const double oldest_s = records_.at(judge_[next]).timestamp_s - options_.window_before_s;
  while (judged_ > 0 && records_.at(judge_.front()).timestamp_s < oldest_s) {
    KeyframeRecord& rec = records_.at(judge_.front());
    if (rec.rejudge_held) {  // held_window_after_s beyond the window: no second look
      reviseOneLocked(judge_.front(), cv::Mat(), cv::Mat(), false);
      rec.rejudge_held = false;
      if (!keepsDepth() && !rec.startup_wait) {  // a startup keyframe is not mapped yet
        rec.depth_u16.release();
        rec.bgr.release();
      }
    }
    if (keepForRevisitsLocked(rec)) {
      revisit_.push_back(judge_.front());
    } else if (!rec.startup_wait) {  // a startup keyframe's view goes with its second look
      rec.view = VisibilityView();
    }
    rec.held = HeldKeyframe();
    judge_.pop_front();
    --judged_;
  }
}

std::vector<cv::Mat> MappingWorker::heldHitsLocked(const std::vector<char>& looked,
                                                   std::vector<cv::Mat>& depth_m) {
  // The window's points (moved out of the records and back); the held pixels of those looked at.
  std::vector<HeldKeyframe> keyframes(judge_.size());
  for (std::size_t i = 0; i < judge_.size(); ++i) {
    KeyframeRecord& rec = records_.at(judge_[i]);
    HeldKeyframe& k = keyframes[i];
    k.T_W_C = rec.T_current;
    k.confirmed_C = std::move(rec.held.confirmed_C);
    k.moved_C = std::move(rec.held.moved_C);
    if (looked[i] != 0 && !rec.held_depth_u16.empty()) {
      rec.held_depth_u16.convertTo(k.depth_m, CV_32FC1, 1.0 / kDepthUnitsPerM);
      k.held = rec.held.held;
    }
  }
  std::vector<cv::Mat> hits = heldConfirmedElsewhere(
      camera_, keyframes, options_.held_revision_voxel_m, options_.held_revision_min_keyframes);
  for (std::size_t i = 0; i < judge_.size(); ++i) {
    KeyframeRecord& rec = records_.at(judge_[i]);
    rec.held.confirmed_C = std::move(keyframes[i].confirmed_C);  // context for later ones
    rec.held.moved_C = std::move(keyframes[i].moved_C);
    depth_m[i] = keyframes[i].depth_m;
  }
  return hits;
}

void MappingWorker::reviseHeldWindowLocked(std::size_t begin, std::size_t end, bool flush) {
  if (options_.held_revision_voxel_m <= 0.0) return;
  ScopedStageTimer timer(timings_, "mapping_held_revision");
  // First looks: [begin, end); second looks: the judged ones due (see rejudge_held).
  const double due_s = records_.at(judge_.back()).timestamp_s - options_.held_window_after_s;
  std::vector<char> looked(judge_.size(), 0);
  bool any = begin < end;
  for (std::size_t i = 0; i < judge_.size(); ++i) {
    const KeyframeRecord& rec = records_.at(judge_[i]);
    const bool second = i < begin && rec.rejudge_held && (flush || rec.timestamp_s <= due_s);
    looked[i] = (i >= begin && i < end) || second ? 1 : 0;
    any = any || second;
  }
  if (!any) return;
  std::vector<cv::Mat> depth_m(judge_.size());
  const std::vector<cv::Mat> hits = heldHitsLocked(looked, depth_m);
  const bool second_look = options_.held_window_after_s > options_.window_after_s;
  for (std::size_t i = 0; i < judge_.size(); ++i) {
    if (looked[i] == 0) continue;
    if (i < begin) {
      secondLookLocked(judge_[i], hits[i], depth_m[i]);
      continue;
    }
    KeyframeRecord& rec = records_.at(judge_[i]);
    const bool keep = second_look && !depth_m[i].empty() && !rec.held.held.empty();
    const cv::Mat revised = reviseOneLocked(judge_[i], hits[i], depth_m[i], keep);
    if (!revised.empty()) revised_masks_[judge_[i]] = revised;
    rec.rejudge_held = keep;
    if (keep) rec.held_hits = hits[i];
  }
}

void MappingWorker::secondLookLocked(std::uint64_t id, const cv::Mat& hit, const cv::Mat& depth_m) {
  KeyframeRecord& rec = records_.at(id);
  const cv::Mat fresh = hit.empty() || rec.held_hits.empty() ? hit : hit & ~rec.held_hits;
  if (!fresh.empty() && cv::countNonZero(fresh) > 0) {
    const cv::Mat all_hits = rec.held_hits.empty() ? hit : hit | rec.held_hits;
    cv::Mat revised = rec.dynamic_mask.clone();
    revised.setTo(0, all_hits);
    revised_masks_[id] = revised;
    const cv::Mat map_mask = rec.extra_mask.empty() ? revised : cv::max(revised, rec.extra_mask);
    StaticPoints sp;  // only the pixels this look unmasked
    sp.static_depth_m = staticDepth(depth_m, map_mask, options_);
    sp.static_depth_m.setTo(0.0f, ~fresh);
    if (cv::countNonZero(sp.static_depth_m > 0.0f) > 0) {
      // A startup keyframe waiting for its second judgement is not mapped yet: the pixels go
      // in with the rest; else now, as its supplement.
      if (!rec.startup_wait) {
        if (backend_->needsPoints()) {
          backProjectDepth(camera_, rec.bgr, sp.static_depth_m, options_.stride, &sp.points_C,
                           &sp.colors);
        }
        backend_->integrate(keyframeView(id | kSupplementBit, rec.timestamp_s, rec.T_current,
                                         camera_, rec.bgr, sp));
        rec.supplemented = true;
        ++supplements_;
      }
      cv::Mat more_u16;  // a rebuild (or the waiting keyframe's mapping) takes them with the rest
      sp.static_depth_m.convertTo(more_u16, CV_16UC1, kDepthUnitsPerM);
      rec.depth_u16 = cv::max(rec.depth_u16, more_u16);
    }
  }
  reviseOneLocked(id, cv::Mat(), cv::Mat(), false);  // releases the held data
  rec.rejudge_held = false;
  rec.held_hits.release();
  if (!keepsDepth() && !rec.startup_wait) {
    rec.depth_u16.release();
    rec.bgr.release();
  }
}

void MappingWorker::removeSeenThroughWindowLocked(std::size_t begin, std::size_t end) {
  if (!options_.visibility.enabled) return;
  // Earlier visits' views first (they are older than the window), then the window's.
  std::vector<std::uint64_t> ids =
      revisitContextLocked(records_.at(judge_[(begin + end) / 2]).T_current);
  const std::size_t offset = ids.size();
  ids.insert(ids.end(), judge_.begin(), judge_.end());
  removeSeenThroughLocked(ids, begin + offset, end + offset, options_.visibility);
}

bool MappingWorker::waitsForStartupLook(const KeyframeRecord& rec) const {
  return options_.visibility.enabled && options_.startup_s > 0.0 &&
         options_.startup_window_after_s > options_.window_after_s &&
         rec.timestamp_s < first_keyframe_s_ + options_.startup_s;
}

void MappingWorker::judgeStartupLocked(bool flush) {
  if (startup_waiting_.empty()) return;
  const double newest_s = judge_.empty() ? 0.0 : records_.at(judge_.back()).timestamp_s;
  // Only what later views saw through: the mask votes had their say in the keyframe's window.
  VisibilityOptions seen_through_only = options_.visibility;
  seen_through_only.mask_min_views = 0;
  seen_through_only.mask_span_s = 0.0;
  seen_through_only.mask_near_px = 0;
  std::size_t done = 0;
  for (; done < startup_waiting_.size(); ++done) {
    const std::uint64_t id = startup_waiting_[done];
    KeyframeRecord& rec = records_.at(id);
    if (!flush && rec.timestamp_s > newest_s - options_.startup_window_after_s) break;
    std::vector<std::uint64_t> ids = revisitContextLocked(rec.T_current);
    ids.erase(std::remove(ids.begin(), ids.end(), id), ids.end());  // its own view judges not
    const auto in_window = std::find(judge_.begin(), judge_.end(), id);
    if (in_window == judge_.end()) ids.push_back(id);
    ids.insert(ids.end(), judge_.begin(), judge_.end());
    const auto target =
        static_cast<std::size_t>(std::find(ids.begin(), ids.end(), id) - ids.begin());
    removeSeenThroughLocked(ids, target, target + 1, seen_through_only);
    rec.startup_wait = false;
    integrateRecordLocked(id);
    if (in_window == judge_.end() && !keepForRevisitsLocked(rec)) rec.view = VisibilityView();
  }
  startup_waiting_.erase(startup_waiting_.begin(),
                         startup_waiting_.begin() + static_cast<std::ptrdiff_t>(done));
}

void MappingWorker::removeSeenThroughLocked(const std::vector<std::uint64_t>& ids,
                                            std::size_t begin, std::size_t end,
                                            const VisibilityOptions& options) {
  ScopedStageTimer timer(timings_, "mapping_visibility");
  std::vector<VisibilityKeyframe> keyframes;
  keyframes.reserve(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    KeyframeRecord& rec = records_.at(ids[i]);
    VisibilityKeyframe k;
    k.static_depth = i >= begin && i < end ? &rec.depth_u16 : nullptr;  // others: views only
    k.metres_per_unit = 1.0 / kDepthUnitsPerM;
    k.T_W_C = rec.T_current;
    k.view = &rec.view;
    k.timestamp_s = rec.timestamp_s;
    keyframes.push_back(k);
  }
  VisibilityResult r = removeSeenThrough(camera_, keyframes, options);
  addVisibilityTimings(r);
  visibility_.elements += r.elements;
  visibility_.seen_through += r.seen_through;
  visibility_.mask_voted += r.mask_voted;
  visibility_.removed_pixels += r.removed_pixels;
  visibility_.element_bytes = std::max(visibility_.element_bytes, r.element_bytes);
  for (std::size_t i = begin; i < end; ++i)
    visibility_.per_keyframe_ms.push_back(r.per_keyframe_ms[i]);
}

void MappingWorker::integrateRecordLocked(std::uint64_t id) {
  KeyframeRecord& rec = records_.at(id);
  {
    ScopedStageTimer timer(timings_, "mapping_integrate");
    StaticPoints sp;
    rec.depth_u16.convertTo(sp.static_depth_m, CV_32FC1, 1.0 / kDepthUnitsPerM);
    if (backend_->needsPoints()) {
      backProjectDepth(camera_, rec.bgr, sp.static_depth_m, options_.stride, &sp.points_C,
                       &sp.colors);
    }
    backend_->integrate(keyframeView(id, rec.timestamp_s, rec.T_current, camera_, rec.bgr, sp));
  }
  rec.T_integrated = rec.T_current;
  rec.integrated = true;
  if (rec.rejudge_held) return;  // kept for the held pixels' second look
  rec.dynamic_mask.release();
  rec.extra_mask.release();
  rec.held_depth_u16.release();
  if (!keepsDepth()) {  // a kInPlace backend follows poses itself: nothing to rebuild from
    rec.depth_u16.release();
    rec.bgr.release();
  }
}

cv::Mat MappingWorker::reviseOneLocked(std::uint64_t id, const cv::Mat& hit, const cv::Mat& depth_m,
                                       bool keep_held) {
  KeyframeRecord& rec = records_.at(id);
  cv::Mat revised;
  if (!hit.empty() && !rec.depth_u16.empty()) {
    revised = rec.dynamic_mask.clone();
    revised.setTo(0, hit);
    const cv::Mat map_mask = rec.extra_mask.empty() ? revised : cv::max(revised, rec.extra_mask);
    staticDepth(depth_m, map_mask, options_).convertTo(rec.depth_u16, CV_16UC1, kDepthUnitsPerM);
  }
  if (keep_held) return revised;
  rec.held.depth_m.release();  // done: its depth and masks are released (its confirmed and
  rec.held.held.release();     // moved points stay while the window holds it)
  rec.held_depth_u16.release();
  rec.dynamic_mask.release();
  rec.extra_mask.release();
  return revised;
}

bool MappingWorker::keepForRevisitsLocked(const KeyframeRecord& rec) const {
  if (options_.window_revisit_keyframes <= 0 || rec.view.near_m.empty()) return false;
  for (const std::uint64_t id : revisit_) {
    const Eigen::Isometry3d& T = records_.at(id).T_current;
    if ((T.translation() - rec.T_current.translation()).norm() < kRevisitSpacingM &&
        angleRad(T, rec.T_current) < kRevisitSpacingRad) {
      return false;
    }
  }
  return true;
}

std::vector<std::uint64_t> MappingWorker::revisitContextLocked(
    const Eigen::Isometry3d& T_W_C) const {
  std::vector<std::pair<double, std::uint64_t>> near;  // (distance, id)
  for (const std::uint64_t id : revisit_) {
    const Eigen::Isometry3d& T = records_.at(id).T_current;
    const double d = (T.translation() - T_W_C.translation()).norm();
    if (d < kRevisitReachM && angleRad(T, T_W_C) < kRevisitReachRad) near.emplace_back(d, id);
  }
  const auto k = std::min(near.size(), static_cast<std::size_t>(options_.window_revisit_keyframes));
  std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(k), near.end());
  std::vector<std::uint64_t> ids;
  for (std::size_t i = 0; i < k; ++i) ids.push_back(near[i].second);
  std::sort(ids.begin(), ids.end(), [this](std::uint64_t a, std::uint64_t b) {
    return records_.at(a).timestamp_s < records_.at(b).timestamp_s;
  });
  return ids;
}

void MappingWorker::addVisibilityTimings(const VisibilityResult& r) {
  if (timings_ == nullptr) return;
  for (const double ms : r.per_keyframe_ms) timings_->add("mapping_visibility_kf", ms);
  timings_->add("mapping_visibility_key", r.key_ms);
  timings_->add("mapping_visibility_add", r.add_ms);
  timings_->add("mapping_visibility_project", r.project_ms);
  timings_->add("mapping_visibility_verdict", r.verdict_ms);
  timings_->add("mapping_visibility_zero", r.zero_ms);
}

}  // namespace dynamap
