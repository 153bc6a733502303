// Viewpoints of the map previews: up direction, top view and two oblique views (map_preview.hpp).
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "map_preview.hpp"

namespace dynamap {
namespace {

constexpr std::size_t kMaxSample = 100000;
constexpr float kPi = 3.14159265358979f;
constexpr float kFrameFill = 0.92f;  ///< fraction of the image the framed points span

std::vector<Eigen::Vector3f> subsample(const std::vector<Eigen::Vector3f>& points,
                                       std::size_t max_points) {
  if (points.size() <= max_points) return points;
  std::vector<Eigen::Vector3f> out;
  out.reserve(max_points);
  const double step = static_cast<double>(points.size()) / static_cast<double>(max_points);
  for (std::size_t i = 0; i < max_points; ++i) {
    out.push_back(points[static_cast<std::size_t>(static_cast<double>(i) * step)]);
  }
  return out;
}

/// Eigenvectors (columns, ascending eigenvalues) of the covariance of the points.
Eigen::Matrix3f principalAxes(const std::vector<Eigen::Vector3f>& points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p.cast<double>();
  mean /= static_cast<double>(std::max<std::size_t>(points.size(), 1));
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : points) {
    const Eigen::Vector3d d = p.cast<double>() - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
  return solver.eigenvectors().cast<float>();
}

/// The q-quantile (0..1) of `values` (reordered).
float quantile(std::vector<float>* values, double q) {
  if (values->empty()) return 0.0f;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(values->size() - 1));
  std::nth_element(values->begin(), values->begin() + static_cast<std::ptrdiff_t>(k),
                   values->end());
  return (*values)[k];
}

/// Robust box of the points in the basis (columns of `axes`): 1st and 99th percentiles.
void robustBox(const std::vector<Eigen::Vector3f>& points, const Eigen::Matrix3f& axes,
               Eigen::Vector3f* lo, Eigen::Vector3f* hi) {
  std::vector<float> c(points.size());
  for (int a = 0; a < 3; ++a) {
    for (std::size_t i = 0; i < points.size(); ++i) c[i] = axes.col(a).dot(points[i]);
    (*lo)[a] = quantile(&c, 0.01);
    (*hi)[a] = quantile(&c, 0.99);
  }
}

/// Sets focal_px, cx, cy so the 1st-99th percentile of the projected points fills the image.
void frameToImage(const std::vector<Eigen::Vector3f>& points, const MapPreviewOptions& options,
                  PreviewCamera* camera) {
  std::vector<float> us, vs;
  us.reserve(points.size());
  vs.reserve(points.size());
  for (const auto& p_W : points) {
    const Eigen::Vector3f p = camera->T_C_W * p_W;
    if (camera->orthographic) {
      us.push_back(p.x());
      vs.push_back(p.y());
    } else if (p.z() > 1e-3f) {
      us.push_back(p.x() / p.z());
      vs.push_back(p.y() / p.z());
    }
  }
  if (us.empty()) return;
  const float u0 = quantile(&us, 0.01), u1 = quantile(&us, 0.99);
  const float v0 = quantile(&vs, 0.01), v1 = quantile(&vs, 0.99);
  const float w = static_cast<float>(options.width), h = static_cast<float>(options.height);
  camera->focal_px =
      kFrameFill * std::min(w / std::max(u1 - u0, 1e-6f), h / std::max(v1 - v0, 1e-6f));
  camera->cx = 0.5f * w - camera->focal_px * 0.5f * (u0 + u1);
  camera->cy = 0.5f * h - camera->focal_px * 0.5f * (v0 + v1);
}

Eigen::Isometry3f lookAt(const Eigen::Vector3f& eye, const Eigen::Vector3f& forward,
                         const Eigen::Vector3f& up) {
  const Eigen::Vector3f z = forward.normalized();
  Eigen::Vector3f x = z.cross(up);
  if (x.norm() < 1e-6f) x = z.unitOrthogonal();
  x.normalize();
  const Eigen::Vector3f y = z.cross(x);
  Eigen::Matrix3f R_C_W;
  R_C_W.row(0) = x.transpose();
  R_C_W.row(1) = y.transpose();
  R_C_W.row(2) = z.transpose();
  Eigen::Isometry3f T_C_W = Eigen::Isometry3f::Identity();
  T_C_W.linear() = R_C_W;
  T_C_W.translation() = -R_C_W * eye;
  return T_C_W;
}

}  // namespace

Eigen::Vector3f estimateUp(const std::vector<Eigen::Vector3f>& points_W,
                           const std::vector<TimedPose>& trajectory) {
  Eigen::Vector3f pca_up = Eigen::Vector3f::UnitZ();
  if (points_W.size() >= 3) pca_up = principalAxes(subsample(points_W, kMaxSample)).col(0);
  if (trajectory.empty()) {
    // No camera to tell the sign: make the largest component positive (deterministic).
    Eigen::Index k = 0;
    pca_up.cwiseAbs().maxCoeff(&k);
    return pca_up[k] < 0 ? Eigen::Vector3f(-pca_up) : pca_up;
  }
  Eigen::Matrix3d xx = Eigen::Matrix3d::Zero();
  Eigen::Vector3d image_up = Eigen::Vector3d::Zero();
  for (const TimedPose& pose : trajectory) {
    const Eigen::Vector3d x = pose.T_W_C.linear().col(0);
    xx += x * x.transpose();
    image_up -= pose.T_W_C.linear().col(1);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(xx);
  const Eigen::Vector3d lambda = solver.eigenvalues();
  Eigen::Vector3d up;
  if (lambda(1) > 0 && lambda(0) / lambda(1) < 0.2) {
    up = solver.eigenvectors().col(0);  // the camera yawed: up is normal to all image x axes
  } else {  // one heading: up is in the plane normal to x, nearest the mean image-up direction
    const Eigen::Vector3d x = solver.eigenvectors().col(2);
    up = image_up - image_up.dot(x) * x;
  }
  if (up.norm() < 1e-9) return pca_up;
  up.normalize();
  if (up.dot(image_up) < 0) up = -up;
  return up.cast<float>();
}

std::vector<PreviewCamera> choosePreviewCameras(const std::vector<Eigen::Vector3f>& points_W,
                                                const std::vector<TimedPose>& trajectory,
                                                const MapPreviewOptions& options) {
  if (points_W.empty()) throw std::invalid_argument("choosePreviewCameras: empty map");
  const std::vector<Eigen::Vector3f> sample = subsample(points_W, kMaxSample);
  const Eigen::Vector3f up = estimateUp(sample, trajectory);
  // Horizontal axes: the widest direction of the map seen from above, and its normal.
  std::vector<Eigen::Vector3f> flat(sample.size());
  for (std::size_t i = 0; i < sample.size(); ++i) flat[i] = sample[i] - sample[i].dot(up) * up;
  Eigen::Vector3f h1 = principalAxes(flat).col(2);
  h1 = (h1 - h1.dot(up) * up);
  if (h1.norm() < 1e-6f) h1 = up.unitOrthogonal();
  h1.normalize();
  const Eigen::Vector3f h2 = up.cross(h1);
  Eigen::Matrix3f axes;
  axes << h1, h2, up;
  Eigen::Vector3f lo, hi;
  robustBox(sample, axes, &lo, &hi);
  const Eigen::Vector3f center = axes * (0.5f * (lo + hi));
  const float radius = std::max(0.5f * (hi - lo).norm(), 1e-3f);

  std::vector<PreviewCamera> cameras;
  PreviewCamera top;
  top.name = "top";
  top.orthographic = true;
  top.up_W = up;
  top.T_C_W = lookAt(center + 2.0f * radius * up, -up, h2);  // image x along h1
  frameToImage(sample, options, &top);
  cameras.push_back(top);

  // The side the scene was seen from: towards the mean camera position.
  Eigen::Vector3f side = -h2;
  if (!trajectory.empty()) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const TimedPose& pose : trajectory) mean += pose.T_W_C.translation();
    Eigen::Vector3f d = (mean / static_cast<double>(trajectory.size())).cast<float>() - center;
    d -= d.dot(up) * up;
    if (d.norm() > 1e-3f) side = d.normalized();
  }
  const float elevation = 35.0f * kPi / 180.0f;
  const float half_fov = 25.0f * kPi / 180.0f;
  const float distance = 1.1f * radius / std::sin(half_fov);
  for (int k = 0; k < 2; ++k) {
    const float azimuth = (k == 0 ? 40.0f : -40.0f) * kPi / 180.0f;
    const Eigen::Vector3f dir_h = Eigen::AngleAxisf(azimuth, up) * side;
    const Eigen::Vector3f dir = std::cos(elevation) * dir_h + std::sin(elevation) * up;
    PreviewCamera cam;
    cam.name = "oblique_" + std::to_string(k + 1);
    cam.up_W = up;
    cam.T_C_W = lookAt(center + distance * dir, -dir, up);
    frameToImage(sample, options, &cam);
    cameras.push_back(cam);
  }
  return cameras;
}

}  // namespace dynamap
