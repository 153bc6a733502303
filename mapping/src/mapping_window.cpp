// MappingWorker's online judgement window (see the class comment in mapping_worker.hpp): each
// keyframe is judged by the held revision and the visibility votes against the keyframes near it
// in time, then integrated. Everything here runs on the thread that holds backend_mutex_.
#include <algorithm>

#include "dynamap/mapping/mapping_worker.hpp"

namespace dynamap {
namespace {

constexpr double kDepthUnitsPerM = 5000.0;  // as mapping_worker.cpp's records

}  // namespace

void MappingWorker::judgeReadyLocked(bool flush) {
  if (judge_.empty()) return;
  const bool judging = options_.visibility.enabled || options_.held_revision_voxel_m > 0.0;
  const double after_s = judging ? options_.window_after_s : 0.0;
  const double newest_s = records_.at(judge_.back()).timestamp_s;
  std::size_t end = judged_;  // targets: [judged_, end)
  while (end < judge_.size() &&
         (flush || records_.at(judge_[end]).timestamp_s <= newest_s - after_s)) {
    ++end;
  }
  if (end > judged_) {
    {
      ScopedStageTimer timer(timings_, "mapping_judge");
      reviseHeldWindowLocked(judged_, end);
      removeSeenThroughWindowLocked(judged_, end);
    }
    for (std::size_t i = judged_; i < end; ++i) integrateRecordLocked(judge_[i]);
    judged_ = end;
  }
  rejudgeHeldLocked(flush);
  // Context older than window_before_s before the next keyframe to judge (or the last judged)
  // leaves the window: its view and confirmed points are released.
  const std::size_t next = std::min(judged_, judge_.size() - 1);
  const double oldest_s = records_.at(judge_[next]).timestamp_s - options_.window_before_s;
  while (judged_ > 0 && records_.at(judge_.front()).timestamp_s < oldest_s) {
    KeyframeRecord& rec = records_.at(judge_.front());
    if (rec.rejudge_held) {  // held_window_after_s beyond the window: no second look
      reviseOneLocked(judge_.front(), cv::Mat(), cv::Mat(), false);
      rec.rejudge_held = false;
      if (!keepsDepth()) {
        rec.depth_u16.release();
        rec.bgr.release();
      }
    }
    rec.view = VisibilityView();
    rec.held = HeldKeyframe();
    judge_.pop_front();
    --judged_;
  }
}

std::vector<cv::Mat> MappingWorker::heldHitsLocked(std::size_t begin, std::size_t end,
                                                   std::vector<cv::Mat>& depth_m) {
  // The window's points (moved out of the records and back); the targets' held pixels too.
  std::vector<HeldKeyframe> keyframes(judge_.size());
  for (std::size_t i = 0; i < judge_.size(); ++i) {
    KeyframeRecord& rec = records_.at(judge_[i]);
    HeldKeyframe& k = keyframes[i];
    k.T_W_C = rec.T_current;
    k.confirmed_C = std::move(rec.held.confirmed_C);
    k.moved_C = std::move(rec.held.moved_C);
    if (i >= begin && i < end && !rec.held_depth_u16.empty()) {
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

void MappingWorker::reviseHeldWindowLocked(std::size_t begin, std::size_t end) {
  if (options_.held_revision_voxel_m <= 0.0) return;
  ScopedStageTimer timer(timings_, "mapping_held_revision");
  std::vector<cv::Mat> depth_m(judge_.size());
  const std::vector<cv::Mat> hits = heldHitsLocked(begin, end, depth_m);
  const bool second_look = options_.held_window_after_s > options_.window_after_s;
  for (std::size_t i = begin; i < end; ++i) {
    KeyframeRecord& rec = records_.at(judge_[i]);
    const bool keep = second_look && !depth_m[i].empty() && !rec.held.held.empty();
    const cv::Mat revised = reviseOneLocked(judge_[i], hits[i], depth_m[i], keep);
    if (!revised.empty()) revised_masks_[judge_[i]] = revised;
    rec.rejudge_held = keep;
    if (keep) rec.held_hits = hits[i];
  }
}

void MappingWorker::rejudgeHeldLocked(bool flush) {
  if (options_.held_revision_voxel_m <= 0.0 || judge_.empty()) return;
  const double newest_s = records_.at(judge_.back()).timestamp_s;
  for (std::size_t i = 0; i < judged_; ++i) {
    const std::uint64_t id = judge_[i];
    KeyframeRecord& rec = records_.at(id);
    if (!rec.rejudge_held) continue;
    if (!flush && rec.timestamp_s > newest_s - options_.held_window_after_s) continue;
    ScopedStageTimer timer(timings_, "mapping_held_second_look");
    std::vector<cv::Mat> depth_m(judge_.size());
    const cv::Mat hit = heldHitsLocked(i, i + 1, depth_m)[i];
    const cv::Mat fresh = hit.empty() || rec.held_hits.empty() ? hit : hit & ~rec.held_hits;
    if (!fresh.empty() && cv::countNonZero(fresh) > 0) {
      const cv::Mat all_hits = rec.held_hits.empty() ? hit : hit | rec.held_hits;
      cv::Mat revised = rec.dynamic_mask.clone();
      revised.setTo(0, all_hits);
      revised_masks_[id] = revised;
      const cv::Mat map_mask = rec.extra_mask.empty() ? revised : cv::max(revised, rec.extra_mask);
      StaticPoints sp;  // only the pixels this look unmasked
      sp.static_depth_m = staticDepth(depth_m[i], map_mask, options_);
      sp.static_depth_m.setTo(0.0f, ~fresh);
      if (cv::countNonZero(sp.static_depth_m > 0.0f) > 0) {
        if (backend_->needsPoints()) {
          backProjectDepth(camera_, rec.bgr, sp.static_depth_m, options_.stride, &sp.points_C,
                           &sp.colors);
        }
        backend_->integrate(keyframeView(id | kSupplementBit, rec.timestamp_s, rec.T_current,
                                         camera_, rec.bgr, sp));
        rec.supplemented = true;
        cv::Mat more_u16;  // a rebuild integrates them with the rest
        sp.static_depth_m.convertTo(more_u16, CV_16UC1, kDepthUnitsPerM);
        rec.depth_u16 = cv::max(rec.depth_u16, more_u16);
      }
    }
    reviseOneLocked(id, cv::Mat(), cv::Mat(), false);  // releases the held data
    rec.rejudge_held = false;
    rec.held_hits.release();
    if (!keepsDepth()) {
      rec.depth_u16.release();
      rec.bgr.release();
    }
  }
}

void MappingWorker::removeSeenThroughWindowLocked(std::size_t begin, std::size_t end) {
  if (!options_.visibility.enabled) return;
  ScopedStageTimer timer(timings_, "mapping_visibility");
  std::vector<VisibilityKeyframe> keyframes;
  keyframes.reserve(judge_.size());
  for (std::size_t i = 0; i < judge_.size(); ++i) {
    KeyframeRecord& rec = records_.at(judge_[i]);
    VisibilityKeyframe k;
    k.static_depth = i >= begin && i < end ? &rec.depth_u16 : nullptr;  // others: views only
    k.metres_per_unit = 1.0 / kDepthUnitsPerM;
    k.T_W_C = rec.T_current;
    k.view = &rec.view;
    k.timestamp_s = rec.timestamp_s;
    keyframes.push_back(k);
  }
  VisibilityResult r = removeSeenThrough(camera_, keyframes, options_.visibility);
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
  rec.held = HeldKeyframe();  // done: its depth and masks are released
  rec.held_depth_u16.release();
  rec.dynamic_mask.release();
  rec.extra_mask.release();
  return revised;
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
