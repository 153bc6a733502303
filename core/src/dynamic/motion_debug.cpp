#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "dynamap/core/dynamic/dynamic_motion_filter.hpp"

namespace dynamap {

cv::Mat drawMotionDebug(const cv::Mat& bgr, const MotionDiagnostics& d, const ClassTable& classes) {
  cv::Mat img = bgr.clone();
  if (!d.mask.empty() && d.mask.size() == img.size()) {
    cv::Mat red(img.size(), CV_8UC3, cv::Scalar(0, 0, 255));
    cv::Mat blended;
    cv::addWeighted(img, 0.55, red, 0.45, 0.0, blended);
    blended.copyTo(img, d.mask);
  }
  for (const auto& o : d.objects) {
    const cv::Scalar colour = o.moving ? cv::Scalar(0, 0, 255) : cv::Scalar(0, 220, 255);
    cv::rectangle(img, o.detection.box, colour, 2);
    char label[96];
    std::snprintf(label, sizeof(label), "%s %.2f %d/%d%s",
                  classes.name(o.detection.class_id).c_str(), o.detection.score, o.dynamic_points,
                  o.points, o.moving ? " MOVING" : "");
    cv::putText(img, label, o.detection.box.tl() + cv::Point2f(2, 14), cv::FONT_HERSHEY_SIMPLEX,
                0.45, colour, 1, cv::LINE_AA);
  }
  const auto& m = d.matches;
  for (std::size_t i = 0; i < m.cur_px.size() && i < m.prev_px.size(); ++i) {
    const bool dyn = i < d.match_is_dynamic.size() && d.match_is_dynamic[i];
    const cv::Scalar colour = dyn ? cv::Scalar(0, 0, 255) : cv::Scalar(0, 200, 0);
    cv::line(img, m.prev_px[i], m.cur_px[i], colour, 1, cv::LINE_AA);
    cv::circle(img, m.cur_px[i], 2, colour, -1, cv::LINE_AA);
  }
  return img;
}

}  // namespace dynamap
