#pragma once

// Keyframes of the synthetic room through the visibility pass (removeSeenThrough()), for the
// tests of its vote rules: each keyframe's frame and the mask the pass is given (which may differ
// from the frame's true mask of the moving box), then what the pass removed.

#include <algorithm>
#include <vector>

#include "dynamap/mapping/visibility.hpp"
#include "synthetic_scene.hpp"

namespace dynamap::test {

class VisibilityPass {
 public:
  /// The next keyframe: its frame and the dynamic mask the pass sees; with `moved_object` the
  /// mask is a moved object's (not a person's: KeyframePacket::moved_object_mask).
  void add(SyntheticFrame frame, const cv::Mat& mask, bool moved_object = false) {
    depths_.push_back(frame.depth_m.clone());
    depths_.back().setTo(0.0f, mask);  // static depth: masked pixels 0, edited by the pass
    frames_.push_back(std::move(frame));
    masks_.push_back(mask);
    object_masks_.push_back(moved_object ? mask : cv::Mat());
  }

  /// Runs the pass over the keyframes added, period_s apart.
  void run(const VisibilityOptions& options, double period_s) {
    std::vector<VisibilityView> views;
    for (std::size_t k = 0; k < frames_.size(); ++k)
      views.push_back(makeVisibilityView(frames_[k].depth_m, masks_[k], options, object_masks_[k]));
    std::vector<VisibilityKeyframe> kfs;
    for (std::size_t k = 0; k < frames_.size(); ++k) {
      VisibilityKeyframe kf{&depths_[k], 1.0, frames_[k].T_W_C, &views[k]};
      kf.timestamp_s = period_s * static_cast<double>(k);
      kfs.push_back(kf);
    }
    result_ = removeSeenThrough(SyntheticScene::camera(), kfs, options);
  }

  /// Share of keyframe k's moving-box pixels (the frame's true mask) that the pass removed.
  double moverRemoved(int k) const {
    const cv::Mat mover = (frames_[k].mask == 255) & (frames_[k].depth_m > 0);
    const cv::Mat kept = mover & (depths_[k] > 0);
    return 1.0 - static_cast<double>(cv::countNonZero(kept)) / std::max(1, cv::countNonZero(mover));
  }
  /// Pixels of the static room the pass removed in keyframe k.
  int staticRemoved(int k) const {
    const cv::Mat removed = (depths_[k] == 0) & (frames_[k].depth_m > 0);
    return cv::countNonZero(removed & (frames_[k].mask == 0));
  }
  int pixels(int k) const { return cv::countNonZero(frames_[k].depth_m > 0); }
  const SyntheticFrame& frame(int k) const { return frames_[k]; }
  const VisibilityResult& result() const { return result_; }

 private:
  std::vector<SyntheticFrame> frames_;
  std::vector<cv::Mat> masks_;
  std::vector<cv::Mat> object_masks_;
  std::vector<cv::Mat> depths_;
  VisibilityResult result_;
};

}  // namespace dynamap::test
