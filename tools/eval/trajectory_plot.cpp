#include "trajectory_plot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>

#include <opencv2/imgproc.hpp>

#include "image_io.hpp"

namespace dynamap {
namespace {

const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGridGrey(225, 225, 225);
const cv::Scalar kGtGrey(110, 110, 110);
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kLineAa = cv::LINE_AA;

/// Pixel rectangle of the plot area and the metric window it shows (equal scale on both axes).
struct Frame {
  cv::Rect area;
  double h_min, v_min, m_per_px;
  cv::Point toPixel(double h, double v) const {
    return {area.x + static_cast<int>(std::lround((h - h_min) / m_per_px)),
            area.y + area.height - static_cast<int>(std::lround((v - v_min) / m_per_px))};
  }
  double hMax() const { return h_min + area.width * m_per_px; }
  double vMax() const { return v_min + area.height * m_per_px; }
};

/// 1, 2 or 5 times a power of ten, close to `raw`.
double niceStep(double raw) {
  if (!(raw > 0.0)) return 1.0;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / power;
  return (f < 1.5 ? 1.0 : f < 3.5 ? 2.0 : f < 7.5 ? 5.0 : 10.0) * power;
}

std::string tickLabel(double value, double step) {
  const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, std::abs(value) < 1e-12 ? 0.0 : value);
  return buffer;
}

void putTextCentered(cv::Mat& img, const std::string& text, cv::Point center, double scale,
                     int thickness = 1, cv::Scalar colour = kBlack) {
  int baseline = 0;
  cv::Size size = cv::getTextSize(text, kFont, scale, thickness, &baseline);
  const int max_width = img.cols - 20;  // shrink long text (e.g. titles) to fit the image
  if (size.width > max_width) {
    scale *= static_cast<double>(max_width) / size.width;
    size = cv::getTextSize(text, kFont, scale, thickness, &baseline);
  }
  cv::putText(img, text, {center.x - size.width / 2, center.y + size.height / 2}, kFont, scale,
              colour, thickness, kLineAa);
}

/// Text rotated by 90 degrees (reading bottom to top), centred on `center`.
void putTextVertical(cv::Mat& img, const std::string& text, cv::Point center, double scale) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, kFont, scale, 1, &baseline);
  cv::Mat patch(size.height + baseline + 4, size.width + 4, CV_8UC3, kWhite);
  cv::putText(patch, text, {2, size.height + 2}, kFont, scale, kBlack, 1, kLineAa);
  cv::rotate(patch, patch, cv::ROTATE_90_COUNTERCLOCKWISE);
  const cv::Rect roi(center.x - patch.cols / 2, center.y - patch.rows / 2, patch.cols, patch.rows);
  if ((roi & cv::Rect(0, 0, img.cols, img.rows)) == roi) patch.copyTo(img(roi));
}

/// The two axes with the largest variance of `points` (larger one first, i.e. horizontal).
std::array<int, 2> topViewAxes(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= std::max<std::size_t>(points.size(), 1);
  Eigen::Vector3d var = Eigen::Vector3d::Zero();
  for (const auto& p : points) var += (p - mean).cwiseAbs2();
  std::array<int, 3> order{0, 1, 2};
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return var[a] > var[b]; });
  return {order[0], order[1]};
}

Frame makeFrame(const cv::Rect& area, const std::vector<Eigen::Vector3d>& points,
                const std::array<int, 2>& axes) {
  double h_lo = 1e300, h_hi = -1e300, v_lo = 1e300, v_hi = -1e300;
  for (const auto& p : points) {
    h_lo = std::min(h_lo, p[axes[0]]), h_hi = std::max(h_hi, p[axes[0]]);
    v_lo = std::min(v_lo, p[axes[1]]), v_hi = std::max(v_hi, p[axes[1]]);
  }
  const double span = std::max({h_hi - h_lo, v_hi - v_lo, 1e-3});
  const double pad = 0.06 * span;
  const double m_per_px =
      std::max((h_hi - h_lo + 2 * pad) / area.width, (v_hi - v_lo + 2 * pad) / area.height);
  const double h_mid = 0.5 * (h_lo + h_hi), v_mid = 0.5 * (v_lo + v_hi);
  return {area, h_mid - 0.5 * area.width * m_per_px, v_mid - 0.5 * area.height * m_per_px,
          m_per_px};
}

void drawAxes(cv::Mat& img, const Frame& f, const std::array<int, 2>& axes) {
  static const char* kAxisNames[3] = {"x [m]", "y [m]", "z [m]"};
  const double step = niceStep(std::max(f.hMax() - f.h_min, f.vMax() - f.v_min) / 8.0);
  const cv::Point bottom_left(f.area.x, f.area.y + f.area.height);
  for (double h = std::ceil(f.h_min / step) * step; h <= f.hMax(); h += step) {
    const int x = f.toPixel(h, f.v_min).x;
    cv::line(img, {x, f.area.y}, {x, bottom_left.y}, kGridGrey, 1);
    cv::line(img, {x, bottom_left.y}, {x, bottom_left.y + 6}, kBlack, 1);
    putTextCentered(img, tickLabel(h, step), {x, bottom_left.y + 20}, 0.45);
  }
  for (double v = std::ceil(f.v_min / step) * step; v <= f.vMax(); v += step) {
    const int y = f.toPixel(f.h_min, v).y;
    cv::line(img, {f.area.x, y}, {f.area.x + f.area.width, y}, kGridGrey, 1);
    cv::line(img, {f.area.x - 6, y}, {f.area.x, y}, kBlack, 1);
    const std::string label = tickLabel(v, step);
    int baseline = 0;
    const cv::Size size = cv::getTextSize(label, kFont, 0.45, 1, &baseline);
    cv::putText(img, label, {f.area.x - 10 - size.width, y + size.height / 2}, kFont, 0.45, kBlack,
                1, kLineAa);
  }
  cv::rectangle(img, f.area, kBlack, 1);
  putTextCentered(img, kAxisNames[axes[0]], {f.area.x + f.area.width / 2, bottom_left.y + 48}, 0.6);
  putTextVertical(img, kAxisNames[axes[1]], {22, f.area.y + f.area.height / 2}, 0.6);
}

/// Colour of `value` in [0, 1] on OpenCV's "turbo" colour map.
cv::Scalar colourOf(const cv::Mat& lut, double value) {
  const int k = std::clamp(static_cast<int>(std::lround(value * 255.0)), 0, 255);
  const cv::Vec3b c = lut.at<cv::Vec3b>(0, k);
  return {static_cast<double>(c[0]), static_cast<double>(c[1]), static_cast<double>(c[2])};
}

cv::Mat makeColourLut() {
  cv::Mat ramp(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) ramp.at<unsigned char>(0, i) = static_cast<unsigned char>(i);
  cv::Mat lut;
  cv::applyColorMap(ramp, lut, cv::COLORMAP_TURBO);
  return lut;
}

void drawColourBar(cv::Mat& img, const cv::Mat& lut, const cv::Rect& bar, double max_cm) {
  for (int y = 0; y < bar.height; ++y) {
    const double value = 1.0 - static_cast<double>(y) / (bar.height - 1);
    cv::line(img, {bar.x, bar.y + y}, {bar.x + bar.width - 1, bar.y + y}, colourOf(lut, value));
  }
  cv::rectangle(img, bar, kBlack, 1);
  const double step = niceStep(max_cm / 6.0);
  for (double v = 0.0; v <= max_cm + 1e-9; v += step) {
    const int y =
        bar.y + bar.height - 1 - static_cast<int>(std::lround(v / max_cm * (bar.height - 1)));
    cv::line(img, {bar.x + bar.width, y}, {bar.x + bar.width + 5, y}, kBlack, 1);
    cv::putText(img, tickLabel(v, step), {bar.x + bar.width + 9, y + 5}, kFont, 0.45, kBlack, 1,
                kLineAa);
  }
  putTextCentered(img, "ATE error [cm]", {bar.x + bar.width / 2, bar.y - 18}, 0.45);
}

void drawLegend(cv::Mat& img, const Frame& f, const cv::Mat& lut) {
  const cv::Rect box(f.area.x + 12, f.area.y + 12, 290, 64);
  cv::rectangle(img, box, kWhite, cv::FILLED);
  cv::rectangle(img, box, kBlack, 1);
  const int x0 = box.x + 12, x1 = box.x + 52;
  cv::line(img, {x0, box.y + 20}, {x1, box.y + 20}, kGtGrey, 2, kLineAa);
  cv::putText(img, "ground truth", {x1 + 10, box.y + 25}, kFont, 0.5, kBlack, 1, kLineAa);
  for (int x = x0; x < x1; ++x) {
    cv::line(img, {x, box.y + 44}, {x + 1, box.y + 44},
             colourOf(lut, static_cast<double>(x - x0) / (x1 - x0)), 3);
  }
  cv::putText(img, "estimate (aligned)", {x1 + 10, box.y + 49}, kFont, 0.5, kBlack, 1, kLineAa);
}

}  // namespace

cv::Mat renderTrajectoryPlot(const std::vector<TimedPose>& gt, const AteResult& ate,
                             const TrajectoryPlotOptions& options) {
  cv::Mat img(options.height, options.width, CV_8UC3, kWhite);
  std::vector<Eigen::Vector3d> gt_points;
  // Ground truth over the time span of the associated pairs only, not the whole recording.
  const double t0 = ate.timestamps_s.empty() ? -1e300 : ate.timestamps_s.front();
  const double t1 = ate.timestamps_s.empty() ? 1e300 : ate.timestamps_s.back();
  for (const TimedPose& p : gt) {
    if (p.timestamp_s >= t0 && p.timestamp_s <= t1) gt_points.push_back(p.T_W_C.translation());
  }
  if (gt_points.empty()) gt_points = ate.gt_positions_m;
  std::vector<Eigen::Vector3d> all_points = gt_points;
  all_points.insert(all_points.end(), ate.est_aligned_m.begin(), ate.est_aligned_m.end());
  if (all_points.empty()) return img;

  const std::array<int, 2> axes = topViewAxes(gt_points);
  const cv::Rect area(90, 70, options.width - 90 - 150, options.height - 70 - 75);
  const Frame frame = makeFrame(area, all_points, axes);
  drawAxes(img, frame, axes);
  const auto px = [&](const Eigen::Vector3d& p) { return frame.toPixel(p[axes[0]], p[axes[1]]); };

  std::vector<cv::Point> gt_line;
  for (const auto& p : gt_points) gt_line.push_back(px(p));
  cv::polylines(img, gt_line, false, kGtGrey, 2, kLineAa);

  const cv::Mat lut = makeColourLut();
  const double max_err =
      ate.errors_m.empty() ? 0.0 : *std::max_element(ate.errors_m.begin(), ate.errors_m.end());
  const double max_cm = std::max(niceStep(max_err * 100.0 / 5.0) *
                                     std::ceil(max_err * 100.0 / niceStep(max_err * 100.0 / 5.0)),
                                 1e-3);
  for (std::size_t k = 1; k < ate.est_aligned_m.size(); ++k) {
    const double e_cm = 50.0 * (ate.errors_m[k - 1] + ate.errors_m[k]);
    cv::line(img, px(ate.est_aligned_m[k - 1]), px(ate.est_aligned_m[k]),
             colourOf(lut, e_cm / max_cm), 2, kLineAa);
  }
  if (!gt_line.empty()) {
    cv::circle(img, gt_line.front(), 6, kBlack, 2, kLineAa);
    cv::putText(img, "start", gt_line.front() + cv::Point(9, -9), kFont, 0.45, kBlack, 1, kLineAa);
  }
  drawLegend(img, frame, lut);
  drawColourBar(img, lut, cv::Rect(area.x + area.width + 45, area.y + 20, 28, area.height - 40),
                max_cm);

  char title[256];
  std::snprintf(title, sizeof(title), "%s%sATE RMSE %.2f cm  (%zu pairs, %s alignment%s)",
                options.title.c_str(), options.title.empty() ? "" : "  -  ",
                ate.error_m.rmse * 100.0, ate.pairs, ate.with_scale ? "sim3" : "se3",
                ate.with_scale ? (", scale " + tickLabel(ate.alignment.scale, 0.001)).c_str() : "");
  putTextCentered(img, title, {options.width / 2, 32}, 0.7, 2);
  return img;
}

void writeTrajectoryPlot(const std::string& png_path, const std::vector<TimedPose>& gt,
                         const AteResult& ate, const TrajectoryPlotOptions& options) {
  writeImageAtomic(png_path, renderTrajectoryPlot(gt, ate, options));
}

}  // namespace dynamap
