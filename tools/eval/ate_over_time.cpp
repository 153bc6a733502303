#include "ate_over_time.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "image_io.hpp"

namespace dynamap {
namespace {

constexpr int kLeft = 80, kRight = 25, kTop = 45, kBottom = 55;
const cv::Scalar kInk(40, 40, 40);
const cv::Scalar kGrid(225, 225, 225);
const cv::Scalar kCurve(180, 100, 30);  // BGR blue
const cv::Scalar kRmse(40, 40, 210);    // BGR red

/// 1, 2 or 5 times a power of ten, about range / target_ticks.
double niceStep(double range, int target_ticks) {
  const double raw = std::max(range, 1e-9) / target_ticks;
  const double base = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * base >= raw) return m * base;
  }
  return 10.0 * base;
}

std::string formatTick(double value, double step) {
  char text[32];
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

void centeredText(cv::Mat* image, const std::string& text, cv::Point center, double scale) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
  cv::putText(*image, text, {center.x - size.width / 2, center.y + size.height / 2},
              cv::FONT_HERSHEY_SIMPLEX, scale, kInk, 1, cv::LINE_AA);
}

void dashedLine(cv::Mat* image, cv::Point a, cv::Point b, const cv::Scalar& color) {
  const double length = std::hypot(b.x - a.x, b.y - a.y);
  for (double s = 0; s < length; s += 12.0) {
    const double e = std::min(s + 7.0, length);
    const cv::Point p(a.x + static_cast<int>((b.x - a.x) * s / length),
                      a.y + static_cast<int>((b.y - a.y) * s / length));
    const cv::Point q(a.x + static_cast<int>((b.x - a.x) * e / length),
                      a.y + static_cast<int>((b.y - a.y) * e / length));
    cv::line(*image, p, q, color, 1, cv::LINE_AA);
  }
}

}  // namespace

cv::Mat renderAteOverTimePlot(const AteResult& ate, const AteOverTimePlotOptions& options) {
  cv::Mat image(options.height, options.width, CV_8UC3, cv::Scalar(255, 255, 255));
  const std::size_t n = std::min(ate.timestamps_s.size(), ate.errors_m.size());
  const double t0 = n > 0 ? ate.timestamps_s.front() : 0.0;
  const double t_max = n > 1 ? std::max(ate.timestamps_s[n - 1] - t0, 1e-3) : 1.0;
  double e_max = 0.0;
  for (std::size_t i = 0; i < n; ++i) e_max = std::max(e_max, ate.errors_m[i] * 100.0);
  const double y_step = niceStep(std::max(e_max, 0.1), 5);
  const double y_top = std::max(y_step, std::ceil(e_max * 1.05 / y_step) * y_step);
  const double x_step = niceStep(t_max, 8);

  const int x0 = kLeft, x1 = options.width - kRight, y0 = options.height - kBottom, y1 = kTop;
  auto px = [&](double t_s, double e_cm) {
    return cv::Point(x0 + static_cast<int>(std::lround((x1 - x0) * t_s / t_max)),
                     y0 - static_cast<int>(std::lround((y0 - y1) * e_cm / y_top)));
  };
  for (double y = 0.0; y <= y_top + 1e-9; y += y_step) {
    const cv::Point p = px(0.0, y);
    cv::line(image, p, {x1, p.y}, kGrid, 1);
    const std::string label = formatTick(y, y_step);
    int baseline = 0;
    const cv::Size size = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &baseline);
    cv::putText(image, label, {x0 - 8 - size.width, p.y + size.height / 2},
                cv::FONT_HERSHEY_SIMPLEX, 0.45, kInk, 1, cv::LINE_AA);
  }
  for (double t = 0.0; t <= t_max + 1e-9; t += x_step) {
    const cv::Point p = px(t, 0.0);
    cv::line(image, {p.x, y1}, p, kGrid, 1);
    cv::line(image, p, {p.x, p.y + 5}, kInk, 1);
    centeredText(&image, formatTick(t, x_step), {p.x, p.y + 16}, 0.45);
  }
  cv::rectangle(image, {x0, y1}, {x1, y0}, kInk, 1);
  std::vector<cv::Point> curve;
  for (std::size_t i = 0; i < n; ++i) {
    curve.push_back(px(ate.timestamps_s[i] - t0, ate.errors_m[i] * 100.0));
  }
  if (curve.size() >= 2) cv::polylines(image, curve, false, kCurve, 2, cv::LINE_AA);
  if (curve.size() == 1) cv::circle(image, curve[0], 3, kCurve, cv::FILLED);

  char title[160];
  if (n > 0) {
    const double rmse_cm = ate.error_m.rmse * 100.0;
    const int y = px(0.0, rmse_cm).y;
    dashedLine(&image, {x0, y}, {x1, y}, kRmse);
    cv::putText(image, "RMSE", {x1 - 48, y - 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, kRmse, 1,
                cv::LINE_AA);
    std::snprintf(title, sizeof(title), "ATE over time: RMSE %.2f cm, max %.2f cm, %zu poses",
                  rmse_cm, e_max, n);
  } else {
    std::snprintf(title, sizeof(title), "ATE over time: no associated poses");
  }
  const std::string full = options.title.empty() ? title : options.title + " - " + title;
  centeredText(&image, full, {(x0 + x1) / 2, kTop / 2}, 0.55);
  centeredText(&image, "time since first pose [s]", {(x0 + x1) / 2, options.height - 14}, 0.5);
  cv::Mat ylabel(30, 160, CV_8UC3, cv::Scalar(255, 255, 255));
  centeredText(&ylabel, "ATE error [cm]", {80, 15}, 0.5);
  cv::rotate(ylabel, ylabel, cv::ROTATE_90_COUNTERCLOCKWISE);
  const int ly = std::max(0, (y0 + y1) / 2 - ylabel.rows / 2);
  if (ly + ylabel.rows <= image.rows)
    ylabel.copyTo(image(cv::Rect(2, ly, ylabel.cols, ylabel.rows)));
  return image;
}

void writeAteOverTimePlot(const std::string& png_path, const AteResult& ate,
                          const AteOverTimePlotOptions& options) {
  writeImageAtomic(png_path, renderAteOverTimePlot(ate, options));
}

}  // namespace dynamap
