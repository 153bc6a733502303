#include "dynamap/core/dynamic/epipolar_check.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>

namespace dynamap {

namespace {

double medianFlow(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b) {
  std::vector<double> d(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) d[i] = cv::norm(a[i] - b[i]);
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

template <typename T>
std::vector<T> select(const std::vector<T>& v, const std::vector<uchar>& keep) {
  std::vector<T> out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (keep[i]) out.push_back(v[i]);
  }
  return out;
}

double transferError(const cv::Matx33d& H, const cv::Point2f& p1, const cv::Point2f& p2) {
  const cv::Vec3d q = H * cv::Vec3d(p1.x, p1.y, 1.0);
  if (std::abs(q[2]) < 1e-12) return 1e9;
  return std::hypot(q[0] / q[2] - p2.x, q[1] / q[2] - p2.y);
}

int countNonZero(const std::vector<uchar>& v) {
  return static_cast<int>(std::count_if(v.begin(), v.end(), [](uchar c) { return c != 0; }));
}

}  // namespace

double symmetricEpipolarDistance(const cv::Matx33d& F, const cv::Point2f& p1,
                                 const cv::Point2f& p2) {
  const cv::Vec3d x1(p1.x, p1.y, 1.0), x2(p2.x, p2.y, 1.0);
  const cv::Vec3d l2 = F * x1;      // line in image 2
  const cv::Vec3d l1 = F.t() * x2;  // line in image 1
  const double e = x2.dot(l2);
  const double n2 = std::hypot(l2[0], l2[1]), n1 = std::hypot(l1[0], l1[1]);
  if (n1 < 1e-12 || n2 < 1e-12) return 0.0;
  return 0.5 * (std::abs(e) / n2 + std::abs(e) / n1);
}

EpipolarResult checkEpipolar(const std::vector<cv::Point2f>& prev_px,
                             const std::vector<cv::Point2f>& cur_px, const EpipolarOptions& o,
                             const std::vector<std::uint8_t>& fit_subset) {
  EpipolarResult r;
  const std::size_t n = std::min(prev_px.size(), cur_px.size());
  r.residual_px.assign(n, 0.f);
  r.is_dynamic.assign(n, 0);
  if (static_cast<int>(n) < std::max(o.min_matches, 8)) return r;
  std::vector<cv::Point2f> p1(prev_px.begin(), prev_px.begin() + n);
  std::vector<cv::Point2f> p2(cur_px.begin(), cur_px.begin() + n);
  if (fit_subset.size() == n) {  // the models are fitted on the subset, every match is checked
    const std::vector<cv::Point2f> all1 = p1, all2 = p2;
    p1 = select(all1, fit_subset), p2 = select(all2, fit_subset);
    if (static_cast<int>(p1.size()) < std::max(o.min_matches, 8)) return r;
    EpipolarResult fit = checkEpipolar(p1, p2, o);
    if (fit.model == EpipolarModel::kNone) return r;
    r.model = fit.model;
    r.F = fit.F;
    for (std::size_t i = 0; i < n; ++i) {
      r.residual_px[i] =
          static_cast<float>(fit.model == EpipolarModel::kHomography
                                 ? transferError(cv::Matx33d(fit.H), all1[i], all2[i])
                                 : symmetricEpipolarDistance(cv::Matx33d(fit.F), all1[i], all2[i]));
      const double thr = (fit.model == EpipolarModel::kHomography ? 2.0 : 1.0) * o.threshold_px;
      r.is_dynamic[i] = r.residual_px[i] > thr;
    }
    return r;
  }
  if (medianFlow(p1, p2) < o.min_parallax_px) return r;

  std::vector<uchar> f_inl, h_inl;
  cv::Mat F =
      cv::findFundamentalMat(p1, p2, cv::USAC_MAGSAC, o.threshold_px, o.confidence, 2000, f_inl);
  if (F.rows != 3 || F.cols != 3) return r;  // RANSAC found nothing (degenerate)
  f_inl.resize(n);
  const int nf = countNonZero(f_inl);
  if (nf < 8) return r;
  // Refit on the inliers (least-squares normalised 8-point).
  const cv::Mat F_ls = cv::findFundamentalMat(select(p1, f_inl), select(p2, f_inl), cv::FM_8POINT);
  if (F_ls.rows == 3 && F_ls.cols == 3) F = F_ls;

  cv::Mat H =
      cv::findHomography(p1, p2, cv::RANSAC, 2.0 * o.threshold_px, h_inl, 2000, o.confidence);
  h_inl.resize(n);
  const bool low_parallax = !H.empty() && countNonZero(h_inl) >= o.homography_inlier_ratio * nf;
  if (low_parallax) {
    // A homography explains the static scene as well as F: F is ill-conditioned. Points off the
    // homography still move differently from the (far / rotating) background.
    H = cv::findHomography(select(p1, h_inl), select(p2, h_inl), 0);
    if (H.empty()) return r;
    r.model = EpipolarModel::kHomography;
    H.convertTo(r.H, CV_64F);
    const cv::Matx33d Hm(H);
    for (std::size_t i = 0; i < n; ++i)
      r.residual_px[i] = static_cast<float>(transferError(Hm, p1[i], p2[i]));
    // Transfer error has ~2x the variance of a point-to-line distance: scale the threshold.
    for (std::size_t i = 0; i < n; ++i) r.is_dynamic[i] = r.residual_px[i] > 2.0 * o.threshold_px;
    return r;
  }
  r.model = EpipolarModel::kFundamental;
  F.convertTo(r.F, CV_64F);
  const cv::Matx33d Fm(r.F);
  for (std::size_t i = 0; i < n; ++i) {
    r.residual_px[i] = static_cast<float>(symmetricEpipolarDistance(Fm, p1[i], p2[i]));
    r.is_dynamic[i] = r.residual_px[i] > o.threshold_px;
  }
  return r;
}

}  // namespace dynamap
