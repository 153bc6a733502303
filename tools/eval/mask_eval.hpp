#pragma once

#include <cstddef>
#include <string>

#include <opencv2/core.hpp>

namespace dynamap {

/// Agreement of estimated dynamic masks with ground-truth person masks encoded as in
/// shared/data/dynamic/README.md: 255 = moving person, 128 = person standing still, 0 = static
/// scene. An estimated mask marks dynamic pixels with 255 (anything else is static); an empty
/// estimate means nothing dynamic.
struct MaskFrameScore {
  std::size_t gt_moving = 0;        ///< ground-truth moving pixels
  std::size_t est_dynamic = 0;      ///< estimated dynamic pixels
  std::size_t intersection = 0;     ///< moving AND estimated
  std::size_t gt_standing = 0;      ///< ground-truth standing-person pixels
  std::size_t standing_masked = 0;  ///< standing-person pixels estimated dynamic
  double iou() const;               ///< NaN when neither mask has a pixel
};

/// Scores one frame. Throws std::invalid_argument when the sizes differ.
MaskFrameScore scoreMask(const cv::Mat& est_mask, const cv::Mat& gt_mask);

/// Sums over frames. mean IoU is averaged over frames where a moving person is visible.
class MaskScoreSummary {
 public:
  void add(const MaskFrameScore& frame);
  std::size_t frames() const { return frames_; }
  std::size_t framesWithMoving() const { return frames_with_moving_; }
  double meanIou() const;              ///< over frames with gt_moving > 0
  double standingMaskedShare() const;  ///< pixel-weighted, over all frames
  double pixelPrecision() const;       ///< estimated dynamic pixels that are moving people
  double pixelRecall() const;          ///< moving-person pixels that are estimated dynamic
  std::string toJson() const;

 private:
  std::size_t frames_ = 0;
  std::size_t frames_with_moving_ = 0;
  double iou_sum_ = 0.0;
  MaskFrameScore total_;
};

}  // namespace dynamap
