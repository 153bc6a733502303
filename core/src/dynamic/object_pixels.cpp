#include "dynamap/core/dynamic/object_pixels.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace dynamap {

namespace {

constexpr double kBinM = 0.1;
constexpr int kBins = 100;  // 0..10 m

/// Dominant depth (m) of the valid pixels of `roi`, 0 if there are too few. With `near_m` > 0
/// only depths within kContinuityM of it compete (the object was there a frame ago). `dropped`
/// (8-bit, roi's size, or empty): pixels read as 0, not the object's.
constexpr double kContinuityM = 0.5;
double depthMode(const cv::Mat& roi, double near_m, const cv::Mat& dropped = cv::Mat()) {
  const bool any_dropped = !dropped.empty();
  const auto value = [&](const float* z_row, const uchar* dropped_row, int x) {
    return any_dropped && dropped_row[x] != 0 ? 0.f : z_row[x];
  };
  std::vector<int> hist(kBins + 2, 0);
  int total = 0;
  for (int y = 0; y < roi.rows; y += 2) {
    const float* z_row = roi.ptr<float>(y);
    const uchar* dropped_row = any_dropped ? dropped.ptr<uchar>(y) : nullptr;
    for (int x = 0; x < roi.cols; x += 2) {
      const float z = value(z_row, dropped_row, x);
      const int b = static_cast<int>(z / kBinM);
      const bool near = near_m <= 0.0 || std::abs(z - near_m) < kContinuityM;
      if (z > 0.f && b < kBins && near) {
        ++hist[b + 1];
        ++total;
      }
    }
  }
  if (total < 20) return 0.0;
  int best = 1;
  for (int b = 1; b <= kBins; ++b) {
    if (hist[b - 1] + 2 * hist[b] + hist[b + 1] > hist[best - 1] + 2 * hist[best] + hist[best + 1])
      best = b;
  }
  const double lo = (best - 2) * kBinM, hi = (best + 1) * kBinM;  // the peak bin +- one bin
  std::vector<float> vals;
  for (int y = 0; y < roi.rows; y += 2) {
    const float* z_row = roi.ptr<float>(y);
    const uchar* dropped_row = any_dropped ? dropped.ptr<uchar>(y) : nullptr;
    for (int x = 0; x < roi.cols; x += 2) {
      const float z = value(z_row, dropped_row, x);
      if (z > lo && z < hi) vals.push_back(z);
    }
  }
  std::nth_element(vals.begin(), vals.begin() + vals.size() / 2, vals.end());
  return vals[vals.size() / 2];
}

/// Not the object's (read as depth 0 below): its pixels on a support plane, and, farther than
/// max_depth_m, where the object would be larger than it can be: that surface is behind it (the
/// wall beside a walker cut by the border, a box left on the wall). Depth compared as float.
/// (A mask, where copying the depth with them zeroed cost twice as much.) Empty: none.
cv::Mat droppedPixels(const cv::Mat& z, const cv::Rect& box, const cv::Mat& not_object,
                      double max_depth_m) {
  cv::Mat dropped;
  if (max_depth_m > 0.0) dropped = z > static_cast<float>(max_depth_m);
  if (!not_object.empty()) {
    const cv::Mat off = not_object(box) != 0;
    dropped = dropped.empty() ? off : (dropped | off);
  }
  return dropped;
}

/// Depth within (lo, hi), compared as float, in one pass; a dropped pixel is selected as depth
/// 0 would be.
cv::Mat depthBand(const cv::Mat& z, const cv::Mat& dropped, float lo, float hi) {
  const uchar dropped_sel = (0.f > lo && 0.f < hi) ? 255 : 0;
  cv::Mat sel(z.size(), CV_8UC1);
  for (int y = 0; y < z.rows; ++y) {
    const float* z_row = z.ptr<float>(y);
    const uchar* dropped_row = dropped.empty() ? nullptr : dropped.ptr<uchar>(y);
    uchar* sel_row = sel.ptr<uchar>(y);
    for (int x = 0; x < z.cols; ++x) {
      sel_row[x] = (dropped_row != nullptr && dropped_row[x] != 0) ? dropped_sel
                   : (z_row[x] > lo && z_row[x] < hi)              ? 255
                                                                   : 0;
    }
  }
  return sel;
}

/// The label (> 0) of `labels` covering most of `inner`, 0 if none.
int labelMostInside(const cv::Mat& labels, int n, const cv::Rect& inner) {
  std::vector<int> votes(n, 0);
  for (int y = inner.y; y < inner.br().y; ++y) {  // a row's labels come in runs
    const int* label = labels.ptr<int>(y);
    for (int x = inner.x; x < inner.br().x;) {
      const int l = label[x];
      const int start = x;
      while (x < inner.br().x && label[x] == l) ++x;
      votes[l] += x - start;
    }
  }
  votes[0] = 0;
  return static_cast<int>(std::max_element(votes.begin(), votes.end()) - votes.begin());
}

}  // namespace

cv::Mat objectPixels(const cv::Mat& depth_m, const cv::Rect& box_in, double band_m,
                     double* depth_mode_m, double prior_depth_m, const cv::Mat& not_object,
                     bool prior_only, double max_depth_m) {
  if (depth_mode_m != nullptr) *depth_mode_m = 0.0;
  const cv::Rect box = box_in & cv::Rect(0, 0, depth_m.cols, depth_m.rows);
  if (box.width < 4 || box.height < 4) return {};
  const cv::Rect inner(box.width / 4, box.height * 15 / 100, std::max(1, box.width / 2),
                       std::max(1, box.height * 70 / 100));  // in the box
  const cv::Mat z = depth_m(box);
  const bool cut = !not_object.empty() || max_depth_m > 0.0;
  const cv::Mat dropped = droppedPixels(z, box, not_object, max_depth_m);
  const cv::Mat dropped_inner = dropped.empty() ? cv::Mat() : dropped(inner);
  double mode = prior_depth_m > 0.0 ? depthMode(z(inner), prior_depth_m, dropped_inner) : 0.0;
  if (mode <= 0.0) {
    mode = depthMode(z(inner), 0.0, dropped_inner);
    // Depth, but none near the prior: with prior_only the object has left the box.
    if (mode > 0.0 && prior_only && prior_depth_m > 0.0)
      return cv::Mat::zeros(depth_m.size(), CV_8UC1);
  }
  if (mode <= 0.0) {
    // No depth at all in the centre of a carried border box (the sensor's blind band at the
    // image edge): nothing there is the object's depth either.
    if (prior_only) return cv::Mat::zeros(depth_m.size(), CV_8UC1);
    const bool has_depth = cut && depthMode(z(inner), 0.0) > 0.0;
    return has_depth ? cv::Mat::zeros(depth_m.size(), CV_8UC1) : cv::Mat();
  }
  if (depth_mode_m != nullptr) *depth_mode_m = mode;
  cv::Mat sel =
      depthBand(z, dropped, static_cast<float>(mode - band_m), static_cast<float>(mode + band_m));
  cv::morphologyEx(sel, sel, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));
  if (!not_object.empty()) sel.setTo(0, not_object(box));
  cv::Mat labels;
  const int n = cv::connectedComponents(sel, labels, 8, CV_32S);
  const int best = labelMostInside(labels, n, inner);
  cv::Mat out = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  if (best > 0) {
    cv::Mat in_box = out(box);
    cv::compare(labels, best, in_box, cv::CMP_EQ);
  }
  return out;
}

}  // namespace dynamap
