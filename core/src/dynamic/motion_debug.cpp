#include <cstdio>
#include <string>

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

std::string objectLogHeader() {
  return "# stamp\tclass\tscore\tx\ty\tw\th\tdepth_m\tpoints\tdynamic\tanchored\t"
         "anchor_px\tanchor_dz_m\tsurface_points\tsurface_dz_m\tquiet\tcarried\tmoving_now\t"
         "moving\n";
}

std::string objectLogLines(double stamp_s, const MotionDiagnostics& d, const ClassTable& classes) {
  std::string out;
  for (const auto& o : d.objects) {
    const auto& b = o.detection.box;
    char line[320];
    std::snprintf(line, sizeof(line),
                  "%.6f\t%s\t%.2f\t%.0f\t%.0f\t%.0f\t%.0f\t%.2f\t%d\t%d\t%d\t%.2f\t%.3f\t"
                  "%d\t%.3f\t%d\t%d\t%d\t%d\n",
                  stamp_s, classes.name(o.detection.class_id).c_str(), o.detection.score, b.x, b.y,
                  b.width, b.height, o.depth_m, o.points, o.dynamic_points, o.anchor.points,
                  o.anchor.median_px, o.anchor.median_dz_m, o.anchor.surface_points,
                  o.anchor.surface_dz_m, o.quiet_frames, o.carried ? 1 : 0, o.moving_now ? 1 : 0,
                  o.moving ? 1 : 0);
    out += line;
  }
  return out;
}

}  // namespace dynamap
