#include "dynamap/core/dynamic/depth_check.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

namespace dynamap {

namespace {

constexpr int kEdgePx = 4;
constexpr float kEdgeM = 0.1f;

enum class Verdict { kNone, kConsistent, kSeenThrough, kOccluded };

/// The view's depth in a window around (u, v) against the point's depth z there.
Verdict judge(const cv::Mat& view_depth, int u, int v, int slack, float z, float margin) {
  float nearest = 0.f;
  bool any = false, consistent = false;
  for (int y = std::max(0, v - slack); y <= std::min(view_depth.rows - 1, v + slack); ++y) {
    const float* row = view_depth.ptr<float>(y);
    for (int x = std::max(0, u - slack); x <= std::min(view_depth.cols - 1, u + slack); ++x) {
      const float d = row[x];
      if (d <= 0.f) continue;
      consistent = consistent || std::abs(d - z) <= margin;
      nearest = any ? std::min(nearest, d) : d;
      any = true;
    }
  }
  if (!any) return Verdict::kNone;
  if (consistent) return Verdict::kConsistent;
  return nearest > z + margin ? Verdict::kSeenThrough : Verdict::kOccluded;
}

/// Median depth of the sampled pixels of group `label` (0 if none has depth); `labels` covers
/// the image from `origin` on.
double groupDepth(const cv::Mat& depth_m, const cv::Mat& labels, cv::Point origin, int label,
                  const cv::Rect& box, int step) {
  std::vector<float> z;
  for (int y = box.y + step / 2; y < box.y + box.height; y += step) {
    for (int x = box.x + step / 2; x < box.x + box.width; x += step) {
      if (labels.at<int>(y - origin.y, x - origin.x) == label && depth_m.at<float>(y, x) > 0.f) {
        z.push_back(depth_m.at<float>(y, x));
      }
    }
  }
  if (z.empty()) return 0.0;
  std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
  return z[z.size() / 2];
}

}  // namespace

double agreementMarginM(double z_m, const DepthCheckOptions& o) {
  return o.noise_sigmas * std::sqrt(2.0) * depthNoiseM(z_m) + o.pose_margin_m +
         o.relative_margin * z_m;
}

bool viewPixel(const cv::Vec4d& p_V, const cv::Vec4d& K, const DepthView& view, int* u, int* v) {
  if (p_V[2] <= 0.1) return false;
  const double sv = view.scale;
  *u = cvRound(sv * (K[0] * p_V[0] / p_V[2] + K[2] + 0.5) - 0.5);
  *v = cvRound(sv * (K[1] * p_V[1] / p_V[2] + K[3] + 0.5) - 0.5);
  return *u >= 0 && *v >= 0 && *u < view.depth_m.cols && *v < view.depth_m.rows;
}

float interiorDepth(const cv::Mat& depth_m, int x, int y) {
  const float z = depth_m.at<float>(y, x);
  if (z <= 0.f) return 0.f;
  const int xs[4] = {x - kEdgePx, x + kEdgePx, x, x};
  const int ys[4] = {y, y, y - kEdgePx, y + kEdgePx};
  for (int k = 0; k < 4; ++k) {
    if (xs[k] < 0 || ys[k] < 0 || xs[k] >= depth_m.cols || ys[k] >= depth_m.rows) return 0.f;
    const float n = depth_m.at<float>(ys[k], xs[k]);
    if (n <= 0.f || std::abs(n - z) > kEdgeM) return 0.f;
  }
  return z;
}

float windowInteriorDepth(const cv::Mat& depth_m, int x, int y, int radius_px, float step_m) {
  const float z = interiorDepth(depth_m, x, y);
  if (z <= 0.f) return 0.f;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const int u = x + dx * radius_px, v = y + dy * radius_px;
      if (u < 0 || v < 0 || u >= depth_m.cols || v >= depth_m.rows) return 0.f;
      const float n = depth_m.at<float>(v, u);
      if (n <= 0.f || std::abs(n - z) > step_m) return 0.f;
    }
  }
  return z;
}

DepthAgreement compareWithView(const cv::Mat& depth_m, const cv::Mat& region, const cv::Rect& roi,
                               const cv::Matx44d& T_W_C, const cv::Vec4d& K, const DepthView& view,
                               const DepthCheckOptions& o, cv::Mat* seen_through) {
  DepthAgreement out;
  if (view.depth_m.empty() || depth_m.empty()) return out;
  const cv::Matx44d T_V_C = view.T_W_C.inv(cv::DECOMP_SVD) * T_W_C;
  const int slack = std::max(1, cvRound(o.slack_px * view.scale));
  const int b = std::max(0, o.border_px);
  const cv::Rect r = roi & cv::Rect(b, b, depth_m.cols - 2 * b, depth_m.rows - 2 * b);
  const int step = std::max(1, o.stride_px);
  for (int y = r.y + step / 2; y < r.y + r.height; y += step) {
    for (int x = r.x + step / 2; x < r.x + r.width; x += step) {
      if (!region.empty() && region.at<uchar>(y, x) == 0) continue;
      const float z = interiorDepth(depth_m, x, y);
      if (z <= 0.f || (o.max_depth_m > 0.0 && z > o.max_depth_m)) continue;
      const cv::Vec4d p_C((x - K[2]) / K[0] * z, (y - K[3]) / K[1] * z, z, 1.0);
      const cv::Vec4d p_V = T_V_C * p_C;
      int u = 0, v = 0;
      if (!viewPixel(p_V, K, view, &u, &v)) continue;
      const double zv = p_V[2];
      const auto margin = static_cast<float>(agreementMarginM(zv, o));
      const Verdict verdict = judge(view.depth_m, u, v, slack, static_cast<float>(zv), margin);
      if (verdict == Verdict::kNone) continue;
      ++out.samples;
      if (verdict == Verdict::kConsistent) ++out.consistent;
      if (verdict == Verdict::kOccluded) ++out.occluded;
      if (verdict == Verdict::kSeenThrough) {
        ++out.seen_through;
        if (seen_through != nullptr) {
          const cv::Rect cell(x - step / 2, y - step / 2, step, step);
          (*seen_through)(cell & cv::Rect(0, 0, depth_m.cols, depth_m.rows)).setTo(255);
        }
      }
    }
  }
  return out;
}

DepthView DepthHistory::halfView(const cv::Mat& depth_m, long frame) {
  DepthView view;
  view.frame = frame;
  view.scale = 0.5;
  // Nearest (not averaged) samples: a mean across an occlusion edge is a depth nobody saw.
  if (!depth_m.empty()) cv::resize(depth_m, view.depth_m, cv::Size(), 0.5, 0.5, cv::INTER_NEAREST);
  return view;
}

void DepthHistory::push(DepthView view) {
  if (max_age_ <= 0 || view.depth_m.empty()) return;
  const long frame = view.frame;
  views_.push_back(std::move(view));
  while (!views_.empty() && views_.front().frame < frame - max_age_) views_.pop_front();
}

bool DepthHistory::followPoseSnap(const cv::Matx44d& T_W_final, const cv::Matx44d& T_W_prior) {
  const cv::Matx44d S = T_W_final * T_W_prior.inv(cv::DECOMP_SVD);
  Eigen::Matrix4d s;
  cv::cv2eigen(S, s);
  const double turned_deg = Eigen::AngleAxisd(s.topLeftCorner<3, 3>()).angle() * 180.0 / M_PI;
  if (s.topRightCorner<3, 1>().norm() <= kPoseSnapM && turned_deg <= kPoseSnapDeg) return false;
  for (DepthView& view : views_) view.T_W_C = S * view.T_W_C;
  return true;
}

const DepthView* DepthHistory::newestUpTo(long last_frame) const {
  for (auto it = views_.rbegin(); it != views_.rend(); ++it) {
    if (it->frame <= last_frame) return &*it;
  }
  return nullptr;
}

cv::Mat depthSteps(const cv::Mat& depth_m, double step_m) {
  cv::Mat out = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  const auto step = [step_m](float a, float b) {
    return a <= 0.f || b <= 0.f || std::abs(a - b) > step_m + 0.01 * std::min(a, b);
  };
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* row = depth_m.ptr<float>(y);
    const float* below = y + 1 < depth_m.rows ? depth_m.ptr<float>(y + 1) : nullptr;
    uchar* o = out.ptr<uchar>(y);
    uchar* o_below = below != nullptr ? out.ptr<uchar>(y + 1) : nullptr;
    for (int x = 0; x < depth_m.cols; ++x) {
      if (x + 1 < depth_m.cols && step(row[x], row[x + 1])) o[x] = o[x + 1] = 1;
      if (below == nullptr) continue;
      if (step(row[x], below[x])) o[x] = o_below[x] = 1;
      if (x + 1 < depth_m.cols && step(row[x], below[x + 1])) o[x] = o_below[x + 1] = 1;
      if (x > 0 && step(row[x], below[x - 1])) o[x] = o_below[x - 1] = 1;
    }
  }
  return out;
}

cv::Mat seenThroughRegions(const cv::Mat& depth_m, const cv::Matx44d& T_W_C, const cv::Vec4d& K,
                           const DepthView& view, const cv::Mat& exclude,
                           const SeenThroughOptions& o, int* regions, const SeedFilter& not_seeds) {
  cv::Mat out = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  if (regions != nullptr) *regions = 0;
  cv::Mat seen = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  compareWithView(depth_m, cv::Mat(), cv::Rect(0, 0, depth_m.cols, depth_m.rows), T_W_C, K, view,
                  o.check, &seen);
  if (!exclude.empty()) seen.setTo(0, exclude);
  // Groups are found only where there is anything (most frames see through little or nothing);
  // each group is handled on its own, so the order of their labels does not matter.
  cv::Rect bound = cv::boundingRect(seen);
  if (bound.area() > 0 && not_seeds) {
    const cv::Mat drop = not_seeds(seen);
    if (!drop.empty()) seen.setTo(0, drop);
    bound = cv::boundingRect(seen);
  }
  if (bound.area() == 0) return out;
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(seen(bound), labels, stats, centroids, 8, CV_32S);
  const cv::Rect image(0, 0, depth_m.cols, depth_m.rows);
  const int step = std::max(1, o.check.stride_px);
  for (int c = 1; c < n; ++c) {
    if (stats.at<int>(c, cv::CC_STAT_AREA) < o.min_region_px) continue;
    const cv::Rect tight(bound.x + stats.at<int>(c, cv::CC_STAT_LEFT),
                         bound.y + stats.at<int>(c, cv::CC_STAT_TOP),
                         stats.at<int>(c, cv::CC_STAT_WIDTH), stats.at<int>(c, cv::CC_STAT_HEIGHT));
    const double z = groupDepth(depth_m, labels, bound.tl(), c, tight, step);
    if (z <= 0.0) continue;
    const int gw = cvRound(o.grow_m * K[0] / z), gh = cvRound(o.grow_m * K[1] / z);
    const cv::Rect roi =
        cv::Rect(tight.x - gw, tight.y - gh, tight.width + 2 * gw, tight.height + 2 * gh) & image;
    cv::Mat flood = cv::Mat::zeros(roi.height + 2, roi.width + 2, CV_8UC1);
    if (!exclude.empty()) flood(cv::Rect(1, 1, roi.width, roi.height)).setTo(1, exclude(roi));
    const cv::Mat depth_roi = depth_m(roi).clone();
    if (o.barrier_step_m > 0.0) {
      cv::Mat inner = flood(cv::Rect(1, 1, roi.width, roi.height));
      inner.setTo(1, depthSteps(depth_roi, o.barrier_step_m));
    }
    const cv::Scalar tol(o.depth_range_m);
    for (int y = tight.y + step / 2; y < tight.y + tight.height; y += step) {
      for (int x = tight.x + step / 2; x < tight.x + tight.width; x += step) {
        if (labels.at<int>(y - bound.y, x - bound.x) != c) continue;
        const cv::Point p(x - roi.x, y - roi.y);
        if (depth_roi.at<float>(p) <= 0.f || flood.at<uchar>(p.y + 1, p.x + 1) != 0) continue;
        cv::floodFill(depth_roi, flood, p, cv::Scalar(), nullptr, tol, tol,
                      8 | cv::FLOODFILL_FIXED_RANGE | cv::FLOODFILL_MASK_ONLY | (255 << 8));
      }
    }
    out(roi).setTo(255, flood(cv::Rect(1, 1, roi.width, roi.height)) == 255);
    if (regions != nullptr) ++*regions;
  }
  return out;
}

}  // namespace dynamap
