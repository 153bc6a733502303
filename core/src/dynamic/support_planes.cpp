#include "dynamap/core/dynamic/support_planes.hpp"

#include "dynamap/core/dynamic/depth_check.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace dynamap {

namespace {

constexpr std::uint64_t kSeed = 0x5eed;
constexpr double kMinNormal = 1e-9;

/// A point and how far off a plane it may lie and still be on it (the noise at its depth).
struct Sample {
  cv::Vec3d p;
  double margin_m;
};

Sample sample(double x, double y, double z, const cv::Vec4d& K, const SupportPlaneOptions& o) {
  return {cv::Vec3d((x - K[2]) / K[0] * z, (y - K[3]) / K[1] * z, z),
          std::clamp(o.noise_sigmas * depthNoiseM(z), o.min_margin_m, o.max_margin_m)};
}

bool onPlane(const Sample& s, const Plane& plane) {
  return std::abs(plane.n.dot(s.p) + plane.d) <= s.margin_m;
}

int countOn(const std::vector<Sample>& samples, const Plane& plane) {
  return static_cast<int>(std::count_if(samples.begin(), samples.end(),
                                        [&](const Sample& s) { return onPlane(s, plane); }));
}

/// The plane through three points (false if they are nearly collinear).
bool planeThrough(const cv::Vec3d& a, const cv::Vec3d& b, const cv::Vec3d& c, Plane* plane) {
  const cv::Vec3d n = (b - a).cross(c - a);
  const double len = cv::norm(n);
  if (len < kMinNormal) return false;
  plane->n = n / len;
  plane->d = -plane->n.dot(a);
  return true;
}

/// Least-squares plane through `points` (their centroid and the direction of least spread).
Plane refit(const std::vector<cv::Vec3d>& points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += Eigen::Vector3d(p[0], p[1], p[2]);
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : points) {
    const Eigen::Vector3d q = Eigen::Vector3d(p[0], p[1], p[2]) - mean;
    cov += q * q.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d n = eig.eigenvectors().col(0);
  Plane plane;
  plane.n = cv::Vec3d(n.x(), n.y(), n.z());
  plane.d = -n.dot(mean);
  return plane;
}

/// The best plane of `samples` by RANSAC, refitted to its inliers.
Plane bestPlane(const std::vector<Sample>& samples, const SupportPlaneOptions& o, cv::RNG& rng) {
  Plane best;
  const int n = static_cast<int>(samples.size());
  for (int it = 0; it < o.iterations; ++it) {
    Plane h;
    if (!planeThrough(samples[rng.uniform(0, n)].p, samples[rng.uniform(0, n)].p,
                      samples[rng.uniform(0, n)].p, &h)) {
      continue;
    }
    h.inliers = countOn(samples, h);
    if (h.inliers > best.inliers) best = h;
  }
  if (best.inliers < 3) return best;
  std::vector<cv::Vec3d> in;
  for (const auto& s : samples) {
    if (onPlane(s, best)) in.push_back(s.p);
  }
  Plane fitted = refit(in);
  fitted.inliers = countOn(samples, fitted);
  return fitted.inliers >= best.inliers ? fitted : best;
}

}  // namespace

std::vector<Plane> findSupportPlanes(const cv::Mat& depth_m, const cv::Vec4d& K,
                                     const cv::Mat& exclude, const SupportPlaneOptions& o) {
  std::vector<Sample> samples;
  const int step = std::max(1, o.stride_px);
  for (int y = step / 2; y < depth_m.rows; y += step) {
    for (int x = step / 2; x < depth_m.cols; x += step) {
      const float z = depth_m.at<float>(y, x);
      if (z <= 0.f || (!exclude.empty() && exclude.at<uchar>(y, x) != 0)) continue;
      samples.push_back(sample(x, y, z, K, o));
    }
  }
  const int needed =
      std::max(o.min_inliers, static_cast<int>(std::ceil(o.min_share * samples.size())));
  std::vector<Plane> planes;
  cv::RNG rng(kSeed);
  while (static_cast<int>(planes.size()) < o.max_planes &&
         static_cast<int>(samples.size()) >= needed) {
    const Plane plane = bestPlane(samples, o, rng);
    if (plane.inliers < needed) break;
    planes.push_back(plane);
    samples.erase(std::remove_if(samples.begin(), samples.end(),
                                 [&](const Sample& s) { return onPlane(s, plane); }),
                  samples.end());
  }
  return planes;
}

cv::Mat planePixels(const cv::Mat& depth_m, const cv::Vec4d& K, const std::vector<Plane>& planes,
                    const SupportPlaneOptions& o) {
  cv::Mat out = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  if (planes.empty()) return out;
  // The back-projection's per-column and per-row factors, computed once (as sample() does).
  std::vector<double> fx(static_cast<std::size_t>(depth_m.cols));
  for (int x = 0; x < depth_m.cols; ++x) fx[static_cast<std::size_t>(x)] = (x - K[2]) / K[0];
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* z_row = depth_m.ptr<float>(y);
    uchar* out_row = out.ptr<uchar>(y);
    const double fy = (y - K[3]) / K[1];
    for (int x = 0; x < depth_m.cols; ++x) {
      if (z_row[x] <= 0.f) continue;
      const double z = z_row[x];
      const Sample s{cv::Vec3d(fx[static_cast<std::size_t>(x)] * z, fy * z, z),
                     std::clamp(o.noise_sigmas * depthNoiseM(z), o.min_margin_m, o.max_margin_m)};
      for (const auto& plane : planes) {
        if (onPlane(s, plane)) {
          out_row[x] = 255;
          break;
        }
      }
    }
  }
  return out;
}

cv::Mat stillPlaneCells(const cv::Mat& depth_m, const cv::Matx44d& T_W_C, const cv::Vec4d& K,
                        const DepthView& view, const std::vector<Plane>& planes,
                        const SupportPlaneOptions& plane_options, const DepthCheckOptions& check,
                        const cv::Mat& candidates) {
  cv::Mat out = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  if (planes.empty() || view.depth_m.empty() || depth_m.empty()) return out;
  const cv::Matx44d T_V_C = view.T_W_C.inv(cv::DECOMP_SVD) * T_W_C;
  const cv::Matx44d T_C_V = T_V_C.inv(cv::DECOMP_SVD);
  const double sv = view.scale;
  const int step = std::max(1, check.stride_px), b = std::max(0, check.border_px);
  const cv::Rect image(0, 0, depth_m.cols, depth_m.rows);
  for (int y = b + step / 2; y < depth_m.rows - b; y += step) {
    for (int x = b + step / 2; x < depth_m.cols - b; x += step) {
      const float z = depth_m.at<float>(y, x);
      if (z <= 0.f || (!candidates.empty() && candidates.at<uchar>(y, x) == 0)) continue;
      const Sample s = sample(x, y, z, K, plane_options);
      const auto own = std::find_if(planes.begin(), planes.end(),
                                    [&](const Plane& plane) { return onPlane(s, plane); });
      if (own == planes.end()) continue;
      int u = 0, v = 0;
      if (!viewPixel(T_V_C * cv::Vec4d(s.p[0], s.p[1], s.p[2], 1.0), K, view, &u, &v)) continue;
      const double zv = view.depth_m.at<float>(v, u);
      if (zv <= 0.0) continue;
      const double xv = (u + 0.5) / sv - 0.5, yv = (v + 0.5) / sv - 0.5;  // full-image pixel
      const cv::Vec4d q_C =
          T_C_V * cv::Vec4d((xv - K[2]) / K[0] * zv, (yv - K[3]) / K[1] * zv, zv, 1.0);
      const double off = std::abs(own->n.dot(cv::Vec3d(q_C[0], q_C[1], q_C[2])) + own->d);
      if (off <= agreementMarginM(zv, check))
        out(cv::Rect(x - step / 2, y - step / 2, step, step) & image).setTo(255);
    }
  }
  return out;
}

}  // namespace dynamap
