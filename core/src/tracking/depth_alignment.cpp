#include "dynamap/core/tracking/depth_alignment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Eigenvalues>
#include <opencv2/core/eigen.hpp>
#include <opencv2/rgbd.hpp>

#include "dynamap/core/rounding.hpp"

namespace dynamap {
namespace {

bool usable(const cv::Mat& mask, int x, int y) { return mask.empty() || mask.at<uchar>(y, x) == 0; }

/// The static points of the current image, in its camera frame.
std::vector<Eigen::Vector3d> currentPoints(const PosedDepth& current, const PinholeCamera& camera,
                                           const DepthAlignmentOptions& o) {
  std::vector<Eigen::Vector3d> points;
  const int step = std::max(1, o.pixel_stride);
  for (int y = step / 2; y < current.depth_m.rows; y += step) {
    const float* row = current.depth_m.ptr<float>(y);
    for (int x = step / 2; x < current.depth_m.cols; x += step) {
      const double z = row[x];
      if (z >= o.min_depth_m && z <= o.max_depth_m && usable(current.moving_mask, x, y)) {
        points.push_back(camera.backProject(x, y, z));
      }
    }
  }
  return points;
}

/// The reference surface at a pixel: its point and unit normal (from the neighbours two pixels
/// away), none where a neighbour is missing, masked, or across a depth step.
struct SurfacePoint {
  Eigen::Vector3d point, normal;
};

bool surfaceAt(const PosedDepth& ref, const PinholeCamera& camera, const DepthAlignmentOptions& o,
               int x, int y, SurfacePoint& out) {
  constexpr int kReach = 2;
  if (x < kReach || y < kReach || x >= ref.depth_m.cols - kReach ||
      y >= ref.depth_m.rows - kReach || !usable(ref.moving_mask, x, y)) {
    return false;
  }
  const auto depth = [&](int u, int v) { return static_cast<double>(ref.depth_m.at<float>(v, u)); };
  const double z = depth(x, y);
  if (!(z >= o.min_depth_m && z <= o.max_depth_m)) return false;
  const double zl = depth(x - kReach, y), zr = depth(x + kReach, y);
  const double zu = depth(x, y - kReach), zd = depth(x, y + kReach);
  const double step = 0.05 * z;
  for (const double n : {zl, zr, zu, zd}) {
    if (!(n > 0.0) || std::abs(n - z) > step) return false;
  }
  const Eigen::Vector3d dx =
      camera.backProject(x + kReach, y, zr) - camera.backProject(x - kReach, y, zl);
  const Eigen::Vector3d dy =
      camera.backProject(x, y + kReach, zd) - camera.backProject(x, y - kReach, zu);
  const Eigen::Vector3d normal = dx.cross(dy);
  if (normal.norm() < 1e-12) return false;
  out.point = camera.backProject(x, y, z);
  out.normal = normal.normalized();
  return true;
}

/// The current points associated with the reference surface at a pose: their point-to-plane
/// residuals n.(T p - r), and the translation block of the normal equations, sum of w n n^T
/// (Huber weights w), which says how well the surfaces pin the translation down.
struct Association {
  Eigen::Matrix3d translation_information = Eigen::Matrix3d::Zero();
  std::vector<double> residuals;
};

Association associate(const PosedDepth& ref, const std::vector<Eigen::Vector3d>& points,
                      const Eigen::Isometry3d& T_R_C, const PinholeCamera& camera,
                      const DepthAlignmentOptions& o) {
  Association association;
  SurfacePoint surface;
  for (const Eigen::Vector3d& p_C : points) {
    const Eigen::Vector3d q = T_R_C * p_C;
    if (q.z() <= 0.0) continue;
    const Eigen::Vector2d px = camera.project(q);
    const int x = static_cast<int>(roundHalfAway(px.x()));
    const int y = static_cast<int>(roundHalfAway(px.y()));
    if (!surfaceAt(ref, camera, o, x, y, surface)) continue;
    if ((q - surface.point).norm() > o.end_gate_m) continue;
    const double e = surface.normal.dot(q - surface.point);
    const double w = std::abs(e) <= o.huber_m ? 1.0 : o.huber_m / std::abs(e);
    association.translation_information += w * surface.normal * surface.normal.transpose();
    association.residuals.push_back(e);
  }
  return association;
}

/// A depth image for OpenCV's odometry: no reading (0) becomes NaN, which it leaves out.
cv::Mat odometryDepth(const cv::Mat& depth_m) {
  cv::Mat d = depth_m.clone();
  d.setTo(std::numeric_limits<float>::quiet_NaN(), d <= 0.f);
  return d;
}

/// OpenCV's mask: nonzero = take part (ours: nonzero = left out).
cv::Mat odometryMask(const cv::Mat& moving_mask, const cv::Size& size) {
  return moving_mask.empty() ? cv::Mat(size, CV_8UC1, cv::Scalar(255)) : cv::Mat(moving_mask == 0);
}

/// The smallest eigenvalue of the translation block of the normal equations.
double weakestDirectionPoints(const Eigen::Matrix3d& translation_information) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(translation_information);
  return solver.eigenvalues().minCoeff();
}

void scoreResult(const Association& association, const DepthAlignmentOptions& o,
                 DepthAlignment& out) {
  double sum_sq = 0.0;
  for (const double e : association.residuals) {
    if (std::abs(e) <= o.inlier_m) {
      ++out.inliers;
      sum_sq += e * e;
    }
  }
  const double associated = static_cast<double>(association.residuals.size());
  out.inlier_share = associated > 0 ? out.inliers / associated : 0.0;
  out.rms_m = out.inliers > 0 ? std::sqrt(sum_sq / out.inliers) : 0.0;
  out.weakest_direction_points = weakestDirectionPoints(association.translation_information);
  out.accepted = out.inliers >= o.min_inliers && out.inlier_share >= o.min_inlier_share &&
                 out.weakest_direction_points >= o.min_weakest_direction_points;
}

/// A posed depth as OpenCV's odometry takes it (its depth pyramid and normals are made once, by
/// the first ICP run, and kept for the next).
cv::Ptr<cv::rgbd::OdometryFrame> odometryFrame(const PosedDepth& d) {
  return cv::rgbd::OdometryFrame::create(cv::Mat(), odometryDepth(d.depth_m),
                                         odometryMask(d.moving_mask, d.depth_m.size()));
}

/// OpenCV's point-to-plane ICP from `T_C_R_guess` (T_C_R maps the reference's points into the
/// current frame), associations up to `max_difference_m` apart; empty if it fails.
cv::Mat icpStep(cv::rgbd::ICPOdometry& icp, cv::Ptr<cv::rgbd::OdometryFrame>& reference,
                cv::Ptr<cv::rgbd::OdometryFrame>& current, double max_difference_m,
                const cv::Mat& T_C_R_guess) {
  icp.setMaxDepthDiff(max_difference_m);
  cv::Mat T_C_R;
  return icp.compute(reference, current, T_C_R, T_C_R_guess) ? T_C_R : cv::Mat();
}

}  // namespace

DepthAlignment alignDepth(const PosedDepth& reference, const PosedDepth& current,
                          const PinholeCamera& camera, const DepthAlignmentOptions& o) {
  DepthAlignment out;
  out.T_W_C = current.T_W_C;
  if (reference.depth_m.type() != CV_32FC1 || current.depth_m.type() != CV_32FC1) return out;
  const cv::Mat K =
      (cv::Mat_<double>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  cv::rgbd::ICPOdometry icp(K, static_cast<float>(o.min_depth_m),
                            static_cast<float>(o.max_depth_m));
  icp.setMaxTranslation(o.max_translation_m);
  icp.setMaxRotation(o.max_rotation_deg);
  cv::Ptr<cv::rgbd::OdometryFrame> ref = odometryFrame(reference), cur = odometryFrame(current);
  // Coarse (far associations, to reach the minimum from the guess), then fine (near ones only).
  cv::Mat guess;
  cv::eigen2cv(Eigen::Matrix4d((current.T_W_C.inverse() * reference.T_W_C).matrix()), guess);
  const cv::Mat coarse = icpStep(icp, ref, cur, o.coarse_depth_difference_m, guess);
  if (coarse.empty()) return out;
  const cv::Mat fine = icpStep(icp, ref, cur, o.fine_depth_difference_m, coarse);
  Eigen::Matrix4d T_C_R;
  cv::cv2eigen(fine.empty() ? coarse : fine, T_C_R);
  const Eigen::Isometry3d T_R_C = Eigen::Isometry3d(T_C_R).inverse();
  out.T_W_C = reference.T_W_C * T_R_C;
  scoreResult(associate(reference, currentPoints(current, camera, o), T_R_C, camera, o), o, out);
  return out;
}

}  // namespace dynamap
