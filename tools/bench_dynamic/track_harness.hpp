#pragma once
// Tracker + motion filter on teddy_dyn_dev (what `dynamap run` does, without mapping): per-frame
// records of what the tracker handed to the filter, scored against the ground-truth masks, and
// the Horn-aligned ATE. Header-only; shared by tools/bench_dynamic/track_bench.cpp and tests.

#include <cmath>
#include <memory>
#include <vector>

#include <Eigen/Geometry>

#include "dynamap/core/dynamic/dynamic_motion_filter.hpp"
#include "dynamap/core/tracker.hpp"
#include "dynamic_harness.hpp"
#include "trajectory_eval.hpp"

namespace dynamap::dynbench {

/// Per-match ground-truth class at the current pixel: 0 moving person, 1 standing, 2 scene.
inline int gtClass(const cv::Mat& gt, const cv::Point2f& p) {
  const int x = std::clamp(cvRound(p.x), 0, gt.cols - 1);
  const int y = std::clamp(cvRound(p.y), 0, gt.rows - 1);
  const uchar g = gt.at<uchar>(y, x);
  return g == 255 ? 0 : (g == 128 ? 1 : 2);
}

/// What one filter() call received and returned, counted by ground-truth class.
struct FilterCall {
  int matches = 0;
  int by_class[3] = {0, 0, 0};          ///< matches on moving / standing / scene pixels
  int dynamic_by_class[3] = {0, 0, 0};  ///< of which flagged dynamic (flag or mask)
  bool same_pair = true;                ///< prev_gray is the previous frame given to filter()
};

/// Forwards to a real filter and records its input/output (the ground truth is set per frame).
class SpyFilter : public MotionFilter {
 public:
  explicit SpyFilter(MotionFilter* inner) : inner_(inner) {}
  void setTruth(const cv::Mat& gt) { gt_ = gt; }
  void beginFrame(const RgbdFrame& frame) override {
    if (inner_ != nullptr) inner_->beginFrame(frame);
  }
  MotionFilterOutput filter(const MotionFilterInput& in) override {
    MotionFilterOutput out = inner_ != nullptr ? inner_->filter(in) : MotionFilterOutput{};
    FilterCall c;
    const FeatureMatches& m = *in.matches;
    c.matches = static_cast<int>(m.cur_px.size());
    for (std::size_t i = 0; i < m.cur_px.size(); ++i) {
      const int k = gtClass(gt_, m.cur_px[i]);
      ++c.by_class[k];
      bool dyn = i < out.match_is_dynamic.size() && out.match_is_dynamic[i] != 0;
      if (!out.dynamic_mask.empty()) {
        const int x = std::clamp(cvRound(m.cur_px[i].x), 0, out.dynamic_mask.cols - 1);
        const int y = std::clamp(cvRound(m.cur_px[i].y), 0, out.dynamic_mask.rows - 1);
        dyn = dyn || out.dynamic_mask.at<uchar>(y, x) == 255;
      }
      c.dynamic_by_class[k] += dyn;
    }
    c.same_pair = last_cur_.empty() || (in.prev_gray != nullptr && in.prev_gray->data != nullptr &&
                                        cv::norm(*in.prev_gray, last_cur_, cv::NORM_L1) == 0.0);
    if (in.cur_gray != nullptr) last_cur_ = in.cur_gray->clone();
    last_ = c;
    return out;
  }
  const FilterCall& last() const { return last_; }

 private:
  MotionFilter* inner_;
  cv::Mat gt_, last_cur_;
  FilterCall last_;
};

struct TrackedFrame {
  double stamp = 0.0;
  TrackingResult result;
  FilterCall call;
  MaskScore score;  ///< of result.dynamic_mask
  Eigen::Isometry3d T_gt = Eigen::Isometry3d::Identity();
};

/// ATE RMSE (tools/eval computeAteOfPairs: Horn alignment without scale) of position pairs
/// already associated; 1e9 when fewer than 3 pairs or the lists differ in length.
inline double ateRmse(const std::vector<Eigen::Vector3d>& est,
                      const std::vector<Eigen::Vector3d>& ref) {
  const auto n = static_cast<Eigen::Index>(est.size());
  if (n < 3 || est.size() != ref.size()) return 1e9;
  Eigen::Matrix3Xd a(3, n), b(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    a.col(i) = est[static_cast<std::size_t>(i)];
    b.col(i) = ref[static_cast<std::size_t>(i)];
  }
  return computeAteOfPairs(a, b, /*with_scale=*/false).error_m.rmse;
}

}  // namespace dynamap::dynbench
