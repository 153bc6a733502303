#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace dynamap {

/// One detected object in image pixels.
struct Detection {
  cv::Rect2f box;
  int class_id = -1;  ///< COCO index (0 = person)
  float score = 0.f;
};

enum class NmsKind {
  kPlain,   ///< per-class hard NMS, one score threshold for all classes
  kRecall,  ///< per-class Gaussian soft-NMS, lower score threshold for high-dynamic classes
};

struct NmsOptions {
  NmsKind kind = NmsKind::kRecall;
  float iou_threshold = 0.45f;    ///< hard NMS suppression IoU
  float score_threshold = 0.25f;  ///< plain NMS and low-dynamic classes
  float soft_sigma = 0.5f;        ///< Gaussian soft-NMS: s *= exp(-iou^2 / sigma)
  float dedup_iou = 0.7f;         ///< kRecall: not applied yet (no pass after soft-NMS uses it)
  std::vector<float> class_score_threshold;  ///< kRecall: per class (empty = score_threshold)
};

float iou(const cv::Rect2f& a, const cv::Rect2f& b);

/// Suppresses duplicates among `candidates` (all scores, any order). Returns detections sorted
/// by decreasing score.
std::vector<Detection> suppressDuplicates(std::vector<Detection> candidates,
                                          const NmsOptions& options);

/// Lowest score a candidate must have to possibly survive `options` (for decoders).
float minCandidateScore(const NmsOptions& options);

}  // namespace dynamap
