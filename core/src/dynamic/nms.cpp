#include "dynamap/core/dynamic/nms.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace dynamap {

namespace {

float thresholdFor(const NmsOptions& o, int class_id) {
  if (o.kind == NmsKind::kRecall && class_id >= 0 &&
      class_id < static_cast<int>(o.class_score_threshold.size())) {
    return o.class_score_threshold[class_id];
  }
  return o.score_threshold;
}

void sortByScore(std::vector<Detection>& d) {
  std::stable_sort(d.begin(), d.end(),
                   [](const Detection& a, const Detection& b) { return a.score > b.score; });
}

/// Hard NMS on one class.
std::vector<Detection> hardNms(std::vector<Detection> dets, float iou_thr, float score_thr) {
  sortByScore(dets);
  std::vector<Detection> kept;
  for (const auto& d : dets) {
    if (d.score < score_thr) break;
    bool suppressed = false;
    for (const auto& k : kept) {
      if (iou(k.box, d.box) > iou_thr) {
        suppressed = true;
        break;
      }
    }
    if (!suppressed) kept.push_back(d);
  }
  return kept;
}

/// Gaussian soft-NMS (Bodla et al. 2017) on one class: overlapping boxes lose score smoothly
/// instead of being dropped, so a second, partly hidden person survives.
std::vector<Detection> softNms(std::vector<Detection> dets, float sigma, float score_thr) {
  std::vector<Detection> kept;
  while (!dets.empty()) {
    auto best = std::max_element(dets.begin(), dets.end(),
                                 [](const auto& a, const auto& b) { return a.score < b.score; });
    if (best->score < score_thr) break;
    const Detection top = *best;
    dets.erase(best);
    kept.push_back(top);
    for (auto& d : dets) {
      const float o = iou(top.box, d.box);
      d.score *= std::exp(-(o * o) / sigma);
    }
  }
  return kept;
}

}  // namespace

float iou(const cv::Rect2f& a, const cv::Rect2f& b) {
  const float inter = (a & b).area();
  const float uni = a.area() + b.area() - inter;
  return uni > 0.f ? inter / uni : 0.f;
}

float minCandidateScore(const NmsOptions& options) {
  float m = options.score_threshold;
  if (options.kind == NmsKind::kRecall) {
    for (float t : options.class_score_threshold) m = std::min(m, t);
  }
  return m;
}

std::vector<Detection> suppressDuplicates(std::vector<Detection> candidates,
                                          const NmsOptions& options) {
  std::map<int, std::vector<Detection>> per_class;
  for (const auto& c : candidates) {
    if (c.score >= thresholdFor(options, c.class_id)) per_class[c.class_id].push_back(c);
  }
  std::vector<Detection> out;
  for (auto& [cls, dets] : per_class) {
    const float thr = thresholdFor(options, cls);
    auto kept = options.kind == NmsKind::kRecall
                    ? softNms(std::move(dets), options.soft_sigma, thr)
                    : hardNms(std::move(dets), options.iou_threshold, thr);
    out.insert(out.end(), kept.begin(), kept.end());
  }
  sortByScore(out);
  return out;
}

}  // namespace dynamap
