#include <algorithm>
#include <cmath>
#include <map>

#include <opencv2/calib3d.hpp>

#include "dynamap/core/dynamic/epipolar_check.hpp"

namespace dynamap {

namespace {

constexpr int kMinFitPoints = 12;
constexpr float kFarDepthM = 12.f;
constexpr int kMinIterations = 120;
constexpr int kPriorMinShareInverse = 5;  ///< a prior needs 1/5 of the fit matches as inliers

/// Depth at `p` if valid and not on a depth edge (5x5 range < 5 % of the depth), else 0.
float stableDepth(const cv::Mat& depth_m, const cv::Point2f& p) {
  const int u = cvRound(p.x), v = cvRound(p.y);
  if (u < 2 || v < 2 || u >= depth_m.cols - 2 || v >= depth_m.rows - 2) return 0.f;
  const float z = depth_m.at<float>(v, u);
  if (!(z > 0.1f && z < 8.f)) return 0.f;
  float lo = z, hi = z;
  for (int dv = -2; dv <= 2; ++dv) {
    const float* row = depth_m.ptr<float>(v + dv);
    for (int du = -2; du <= 2; ++du) {
      const float d = row[u + du];
      if (d <= 0.f) return 0.f;
      lo = std::min(lo, d), hi = std::max(hi, d);
    }
  }
  return hi - lo < 0.05f * z ? z : 0.f;
}

/// True if the sensor measured nothing around `p` (away from the image border, where depth
/// sensors never measure): a surface beyond the depth range.
bool beyondRange(const cv::Mat& depth_m, const cv::Point2f& p) {
  const int u = cvRound(p.x), v = cvRound(p.y);
  if (u < 32 || v < 16 || u >= depth_m.cols - 32 || v >= depth_m.rows - 16) return false;
  for (int dv = -3; dv <= 3; ++dv) {
    const float* row = depth_m.ptr<float>(v + dv);
    for (int du = -3; du <= 3; ++du) {
      if (row[u + du] > 0.f) return false;
    }
  }
  return true;
}

/// True if 90 % of the matches moved less than `px`: nothing moved in the image at all (a
/// repeated frame); the flags would carry no information about movers.
bool nothingMoved(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b, double px) {
  std::vector<double> d(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) d[i] = cv::norm(a[i] - b[i]);
  const auto k = static_cast<std::ptrdiff_t>(d.size() * 9 / 10);
  std::nth_element(d.begin(), d.begin() + k, d.end());
  return d[static_cast<std::size_t>(k)] < px;
}

struct PoseFit {
  cv::Mat rvec, tvec;
  std::vector<int> inliers;  ///< indices into the fit arrays
  bool ok = false;
  bool from_prior = false;
};

/// Points within `threshold_px` of the pose's reprojection and their summed weight.
double scorePose(const std::vector<cv::Point3f>& X, const std::vector<cv::Point2f>& p,
                 const std::vector<float>& w, const cv::Matx33d& K, const cv::Mat& rvec,
                 const cv::Mat& tvec, double threshold_px, std::vector<int>* inliers) {
  std::vector<cv::Point2f> proj;
  cv::projectPoints(X, rvec, tvec, K, cv::noArray(), proj);
  double score = 0.0;
  if (inliers != nullptr) inliers->clear();
  for (std::size_t k = 0; k < X.size(); ++k) {
    if (cv::norm(proj[k] - p[k]) > threshold_px) continue;
    score += w[k];
    if (inliers != nullptr) inliers->push_back(static_cast<int>(k));
  }
  return score;
}

/// Levenberg-Marquardt on the inliers of f's pose (twice).
PoseFit refinePose(const std::vector<cv::Point3f>& X, const std::vector<cv::Point2f>& p,
                   const std::vector<float>& w, const cv::Matx33d& K, double threshold_px,
                   PoseFit f) {
  for (int round = 0; round < 2; ++round) {
    scorePose(X, p, w, K, f.rvec, f.tvec, threshold_px, &f.inliers);
    if (static_cast<int>(f.inliers.size()) < kMinFitPoints / 2) return f;
    std::vector<cv::Point3f> ix;
    std::vector<cv::Point2f> ip;
    for (int k : f.inliers) ix.push_back(X[k]), ip.push_back(p[k]);
    cv::solvePnPRefineLM(ix, ip, K, cv::noArray(), f.rvec, f.tvec);
  }
  f.ok = true;
  return f;
}

/// RANSAC over minimal 4-point (AP3P) samples scored by the summed weight of the inliers (so
/// matches on likely movers count less), then Levenberg-Marquardt on the inliers (twice).
/// Adaptive number of iterations (at least kMinIterations, at most `iterations`).
/// Deterministic (fixed seed).
PoseFit fitPose(const std::vector<cv::Point3f>& X, const std::vector<cv::Point2f>& p,
                const std::vector<float>& w, const cv::Matx33d& K, double threshold_px,
                int iterations, const RigidMotion* prior) {
  PoseFit f;
  const int n = static_cast<int>(X.size());
  if (n < kMinFitPoints) return f;
  if (prior != nullptr && prior->valid) {
    // The tracker's map-based motion: taken (and refined on its inliers) when enough of the
    // matches agree with it, whatever a larger moving majority would vote for.
    f.rvec = cv::Mat(prior->rvec).clone();
    f.tvec = cv::Mat(prior->tvec).clone();
    std::vector<int> inl;
    scorePose(X, p, w, K, f.rvec, f.tvec, threshold_px, &inl);
    if (static_cast<int>(inl.size()) >= std::max(kMinFitPoints, n / kPriorMinShareInverse)) {
      f.from_prior = true;
      return refinePose(X, p, w, K, threshold_px, f);
    }
    f.rvec.release(), f.tvec.release();
  }
  cv::RNG rng(0x5eed);
  double best = 0.0;
  int needed = iterations;
  std::vector<cv::Point3f> sx(4);
  std::vector<cv::Point2f> sp(4);
  for (int it = 0; it < std::min(iterations, std::max(kMinIterations, needed)); ++it) {
    int idx[4];
    for (int k = 0; k < 4; ++k) {
      do {
        idx[k] = rng.uniform(0, n);
      } while (std::find(idx, idx + k, idx[k]) != idx + k);
      sx[k] = X[idx[k]], sp[k] = p[idx[k]];
    }
    cv::Mat rvec, tvec;
    if (!cv::solvePnP(sx, sp, K, cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_AP3P)) continue;
    std::vector<int> inl;
    const double score = scorePose(X, p, w, K, rvec, tvec, threshold_px, &inl);
    if (score <= best) continue;
    best = score, f.rvec = rvec, f.tvec = tvec;
    // Adaptive stop (99.9 % to draw one all-inlier sample), never before kMinIterations.
    const double ratio = static_cast<double>(inl.size()) / n;
    const double miss = 1.0 - ratio * ratio * ratio * ratio;
    needed = miss <= 1e-9 ? 0 : static_cast<int>(std::ceil(std::log(1e-3) / std::log(miss)));
    if (it + 1 >= std::max(kMinIterations, needed)) break;
  }
  if (f.rvec.empty()) return f;
  return refinePose(X, p, w, K, threshold_px, f);
}

/// The current frame's matches lifted to 3-D with its depth.
struct LiftedPoints {
  std::vector<cv::Point3f> X;  ///< per match, in the current camera (0 without depth)
  std::vector<float> z;        ///< per match: its stable measured depth (0 = none)
  std::vector<int> fit;        ///< bucketed subset with depth (at most 2 per cell)
};

LiftedPoints liftPoints(const std::vector<cv::Point2f>& cur_px, std::size_t n,
                        const cv::Mat& depth_m, const cv::Vec4d& K, int bucket_px) {
  LiftedPoints l;
  l.X.resize(n);
  l.z.resize(n);
  std::map<std::pair<int, int>, int> cells;
  const int bucket = std::max(1, bucket_px);
  for (std::size_t i = 0; i < n; ++i) {
    l.z[i] = stableDepth(depth_m, cur_px[i]);
    // Points beyond the depth range join the fit as far points (they pin the rotation, which a
    // near, nearly planar static layer leaves ambiguous with translation); their residual
    // is the epipolar distance.
    const float z_fit =
        l.z[i] > 0.f ? l.z[i] : (beyondRange(depth_m, cur_px[i]) ? kFarDepthM : 0.f);
    l.X[i] = cv::Point3f(static_cast<float>((cur_px[i].x - K[2]) * z_fit / K[0]),
                         static_cast<float>((cur_px[i].y - K[3]) * z_fit / K[1]), z_fit);
    if (z_fit <= 0.f) continue;
    auto& c = cells[{cvFloor(cur_px[i].x / bucket), cvFloor(cur_px[i].y / bucket)}];
    if (c++ < 2) l.fit.push_back(static_cast<int>(i));
  }
  return l;
}

/// The camera motion fitted (fitPose()) on the bucketed subset, each match with its weight.
PoseFit fitBackground(const LiftedPoints& l, const std::vector<cv::Point2f>& prev_px,
                      const std::vector<float>& fit_weight, const cv::Matx33d& Km,
                      const EpipolarOptions& o, const RigidMotion* prior) {
  std::vector<cv::Point3f> fx;
  std::vector<cv::Point2f> fp;
  std::vector<float> fw;
  for (int i : l.fit) {
    fx.push_back(l.X[i]), fp.push_back(prev_px[i]);
    fw.push_back(static_cast<std::size_t>(i) < fit_weight.size() ? fit_weight[i] : 1.f);
  }
  const double fit_thr = 0.5 * o.reprojection_threshold_px;
  return fitPose(fx, fp, fw, Km, fit_thr, o.ransac_iterations, prior);
}

/// F of the pose (previous -> current): X_cur = R^T (X_prev - t).
cv::Matx33d fundamentalOf(const PoseFit& pose, const cv::Matx33d& Km) {
  cv::Matx33d R;
  cv::Rodrigues(pose.rvec, R);
  const cv::Vec3d t(pose.tvec.at<double>(0), pose.tvec.at<double>(1), pose.tvec.at<double>(2));
  const cv::Matx33d Rc = R.t();
  const cv::Vec3d tc = -(Rc * t);
  const cv::Matx33d tx(0, -tc[2], tc[1], tc[2], 0, -tc[0], -tc[1], tc[0], 0);
  const cv::Matx33d Kinv = Km.inv();
  return Kinv.t() * tx * Rc * Kinv;
}

/// Each match's residual against the pose: reprojection error with depth, epipolar distance
/// without; flagged beyond its threshold.
void flagByPose(const LiftedPoints& l, const std::vector<cv::Point2f>& prev_px,
                const std::vector<cv::Point2f>& cur_px, const PoseFit& pose, const cv::Matx33d& Km,
                const EpipolarOptions& o, EpipolarResult& r) {
  const cv::Matx33d F = fundamentalOf(pose, Km);
  r.model = EpipolarModel::kRigid;
  r.from_prior = pose.from_prior;
  r.F = cv::Mat(F).clone();
  std::vector<cv::Point2f> proj;
  cv::projectPoints(l.X, pose.rvec, pose.tvec, Km, cv::noArray(), proj);
  for (std::size_t i = 0; i < l.X.size(); ++i) {
    if (l.z[i] > 0.f) {
      r.residual_px[i] = static_cast<float>(cv::norm(proj[i] - prev_px[i]));
      r.is_dynamic[i] = r.residual_px[i] > o.reprojection_threshold_px;
    } else {
      r.residual_px[i] = static_cast<float>(symmetricEpipolarDistance(F, prev_px[i], cur_px[i]));
      r.is_dynamic[i] = r.residual_px[i] > o.rigid_epipolar_threshold_px;
    }
  }
}

}  // namespace

EpipolarResult checkRigidMotion(const std::vector<cv::Point2f>& prev_px,
                                const std::vector<cv::Point2f>& cur_px, const cv::Mat& depth_m,
                                const cv::Vec4d& K, const std::vector<float>& fit_weight,
                                const EpipolarOptions& o, RigidMotion* estimated,
                                const RigidMotion* prior) {
  if (estimated != nullptr) *estimated = RigidMotion{};
  const std::size_t n = std::min(prev_px.size(), cur_px.size());
  EpipolarResult r;
  r.residual_px.assign(n, 0.f);
  r.is_dynamic.assign(n, 0);
  if (static_cast<int>(n) < std::max(o.min_matches, 8) || depth_m.empty()) {
    return depth_m.empty() ? checkEpipolar(prev_px, cur_px, o) : r;
  }
  // No median-parallax guard: with depth a still camera is well-conditioned (PnP), and a walker
  // seen from it must be found. Only a repeated frame (nothing moved) says nothing (kNone).
  if (nothingMoved(prev_px, cur_px, o.min_parallax_px)) return r;
  const LiftedPoints l = liftPoints(cur_px, n, depth_m, K, o.bucket_px);
  // Far points only pin the rotation of a fit made of measured depth: with too little depth
  // (mostly invalid pixels) every point would look "far" and the fit would treat a near scene as
  // if it were 12 m away.
  const auto measured =
      std::count_if(l.fit.begin(), l.fit.end(), [&](int i) { return l.z[i] > 0.f; });
  if (measured < kMinFitPoints) return checkEpipolar(prev_px, cur_px, o);
  const cv::Matx33d Km(K[0], 0, K[2], 0, K[1], K[3], 0, 0, 1);
  const PoseFit best = fitBackground(l, prev_px, fit_weight, Km, o, prior);
  if (!best.ok) return checkEpipolar(prev_px, cur_px, o);
  if (estimated != nullptr) {
    *estimated = RigidMotion{cv::Vec3d(best.rvec), cv::Vec3d(best.tvec), true};
  }
  flagByPose(l, prev_px, cur_px, best, Km, o, r);
  return r;
}

}  // namespace dynamap
