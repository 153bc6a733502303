#include "mask_eval.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/core.hpp>

#include "json_io.hpp"

namespace dynamap {

double MaskFrameScore::iou() const {
  const std::size_t uni = gt_moving + est_dynamic - intersection;
  return uni == 0 ? std::numeric_limits<double>::quiet_NaN()
                  : static_cast<double>(intersection) / static_cast<double>(uni);
}

MaskFrameScore scoreMask(const cv::Mat& est_mask, const cv::Mat& gt_mask) {
  CV_Assert(gt_mask.type() == CV_8UC1);
  if (!est_mask.empty() && est_mask.size() != gt_mask.size()) {
    throw std::invalid_argument("mask sizes differ");
  }
  MaskFrameScore s;
  for (int v = 0; v < gt_mask.rows; ++v) {
    const auto* g = gt_mask.ptr<std::uint8_t>(v);
    const auto* e = est_mask.empty() ? nullptr : est_mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < gt_mask.cols; ++u) {
      const bool dyn = e != nullptr && e[u] == 255;
      const bool moving = g[u] == 255;
      const bool standing = g[u] == 128;
      s.est_dynamic += dyn;
      s.gt_moving += moving;
      s.intersection += dyn && moving;
      s.gt_standing += standing;
      s.standing_masked += dyn && standing;
    }
  }
  return s;
}

void MaskScoreSummary::add(const MaskFrameScore& f) {
  ++frames_;
  if (f.gt_moving > 0) {
    ++frames_with_moving_;
    iou_sum_ += f.iou();
  }
  total_.gt_moving += f.gt_moving;
  total_.est_dynamic += f.est_dynamic;
  total_.intersection += f.intersection;
  total_.gt_standing += f.gt_standing;
  total_.standing_masked += f.standing_masked;
}

namespace {
double ratio(std::size_t a, std::size_t b) {
  return b == 0 ? std::numeric_limits<double>::quiet_NaN()
                : static_cast<double>(a) / static_cast<double>(b);
}
}  // namespace

double MaskScoreSummary::meanIou() const {
  return frames_with_moving_ == 0 ? std::numeric_limits<double>::quiet_NaN()
                                  : iou_sum_ / static_cast<double>(frames_with_moving_);
}
double MaskScoreSummary::standingMaskedShare() const {
  return ratio(total_.standing_masked, total_.gt_standing);
}
double MaskScoreSummary::pixelPrecision() const {
  return ratio(total_.intersection, total_.est_dynamic);
}
double MaskScoreSummary::pixelRecall() const {
  return ratio(total_.intersection, total_.gt_moving);
}

std::string MaskScoreSummary::toJson() const {
  const Json o = {{"frames", frames_},
                  {"frames_with_moving", frames_with_moving_},
                  {"mean_iou", meanIou()},
                  {"standing_masked_share", standingMaskedShare()},
                  {"pixel_precision", pixelPrecision()},
                  {"pixel_recall", pixelRecall()}};
  return dumpJson(o);
}

}  // namespace dynamap
