#include "dynamap/core/dynamic/mover_regions.hpp"

#include <opencv2/imgproc.hpp>

#include "dynamap/core/dynamic/object_pixels.hpp"

namespace dynamap {
namespace {
constexpr int kPersonMarginPx = 5;  ///< notMovers(): around a person's own pixels
constexpr int kWalkerTouchPx = 15;  ///< moverDetections(): a region this near a walker is his

/// A high-dynamic detection's own pixels in its box (objectPixels(); CV_8UC1 of `box`'s size),
/// empty where the box holds no depth or the class is not high-dynamic.
cv::Mat ownPixelsInBox(const cv::Mat& depth_m, const Detection& d, const cv::Rect& box,
                       const ClassTable& classes, double band_m) {
  if (!classes.isHighDynamic(d.class_id) || box.area() <= 0) return {};
  double mode = 0.0;
  const cv::Mat own = objectPixels(depth_m, box, band_m, &mode);
  return own.empty() ? cv::Mat() : own(box).clone();
}
}  // namespace

std::vector<Detection> moverDetections(const cv::Mat& depth_m, const cv::Matx44d& T_W_C,
                                       const cv::Vec4d& K, const DepthView& view,
                                       const cv::Mat& exclude, const SeenThroughOptions& options,
                                       int* regions, const cv::Mat& walkers) {
  std::vector<Detection> out;
  if (regions != nullptr) *regions = 0;
  const cv::Mat moved = seenThroughRegions(depth_m, T_W_C, K, view, exclude, options, regions);
  const cv::Rect bound = cv::boundingRect(moved);
  if (bound.area() == 0) return out;
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(moved(bound), labels, stats, centroids, 8, CV_32S);
  cv::Mat near_walkers;
  if (!walkers.empty()) {
    cv::dilate(walkers(bound), near_walkers,
               cv::getStructuringElement(cv::MORPH_ELLIPSE,
                                         {2 * kWalkerTouchPx + 1, 2 * kWalkerTouchPx + 1}));
  }
  for (int c = 1; c < n; ++c) {
    if (stats.at<int>(c, cv::CC_STAT_AREA) < options.min_region_px) continue;
    if (!near_walkers.empty() && cv::countNonZero((labels == c) & near_walkers) > 0) continue;
    const cv::Rect2f box(static_cast<float>(bound.x + stats.at<int>(c, cv::CC_STAT_LEFT)),
                         static_cast<float>(bound.y + stats.at<int>(c, cv::CC_STAT_TOP)),
                         static_cast<float>(stats.at<int>(c, cv::CC_STAT_WIDTH)),
                         static_cast<float>(stats.at<int>(c, cv::CC_STAT_HEIGHT)));
    out.push_back(Detection{box, ClassTable::kMover, 1.f});
  }
  return out;
}

cv::Mat notMovers(const cv::Mat& depth_m, const cv::Mat& kept_movers, const cv::Mat& planes,
                  const std::vector<Detection>& detections, const ClassTable& classes,
                  double band_m) {
  const cv::Size size = depth_m.size();
  cv::Mat out = kept_movers.empty() ? cv::Mat::zeros(size, CV_8UC1) : kept_movers.clone();
  if (!planes.empty()) out |= planes;
  const cv::Mat margin = cv::getStructuringElement(
      cv::MORPH_ELLIPSE, {2 * kPersonMarginPx + 1, 2 * kPersonMarginPx + 1});
  for (const auto& d : detections) {
    const cv::Rect box = cv::Rect(d.box) & cv::Rect(0, 0, size.width, size.height);
    if (!classes.isHighDynamic(d.class_id) || box.area() <= 0) continue;
    const cv::Mat own = ownPixelsInBox(depth_m, d, box, classes, band_m);
    if (own.empty()) {  // no depth in the box: all of it
      out(box).setTo(255);
      continue;
    }
    cv::Mat grown;
    cv::dilate(own, grown, margin);
    out(box) |= grown;
  }
  return out;
}

cv::Mat peoplePixels(const cv::Mat& depth_m, const std::vector<Detection>& detections,
                     const ClassTable& classes, double band_m) {
  cv::Mat out = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  for (const auto& d : detections) {
    const cv::Rect box = cv::Rect(d.box) & cv::Rect(0, 0, depth_m.cols, depth_m.rows);
    const cv::Mat own = ownPixelsInBox(depth_m, d, box, classes, band_m);
    if (!own.empty()) out(box) |= own;
  }
  return out;
}

cv::Mat keptMovers(const FusionResult& fused) {
  const cv::Mat& kept = fused.static_objects;
  cv::Mat out = cv::Mat::zeros(kept.size(), CV_8UC1);
  const cv::Rect image(0, 0, kept.cols, kept.rows);
  for (const auto& o : fused.objects) {
    const cv::Rect box = cv::Rect(o.detection.box) & image;
    if (o.detection.class_id != ClassTable::kMover || o.moving || box.area() <= 0) continue;
    kept(box).copyTo(out(box), kept(box));
  }
  return out;
}

}  // namespace dynamap
