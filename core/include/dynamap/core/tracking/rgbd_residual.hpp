#pragma once

// Internal to dynamap_core's tracking sources: needs Ceres (a private dependency of the core).

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "dynamap/core/camera.hpp"

namespace dynamap {

/// Whitened RGB-D observation residual: reprojection (2, in pixel sigmas) plus measured depth
/// (1, in depth sigmas; zero when the pixel had no depth). Pose block = T_C_W as
/// (angle-axis[3], translation[3]); point block = p_W.
struct RgbdResidual {
  RgbdResidual(const PinholeCamera& camera, const Eigen::Vector2d& px, double depth_m,
               double inv_sigma_px, double inv_sigma_z)
      : fx(camera.fx),
        fy(camera.fy),
        cx(camera.cx),
        cy(camera.cy),
        u(px.x()),
        v(px.y()),
        z(depth_m),
        w_px(inv_sigma_px),
        w_z(depth_m > 0.0 ? inv_sigma_z : 0.0) {}

  template <typename T>
  bool operator()(const T* pose, const T* point, T* r) const {
    T p[3];
    ceres::AngleAxisRotatePoint(pose, point, p);
    p[0] += pose[3];
    p[1] += pose[4];
    p[2] += pose[5];
    if (p[2] < T(1e-3)) p[2] = T(1e-3);
    r[0] = (T(fx) * p[0] / p[2] + T(cx) - T(u)) * T(w_px);
    r[1] = (T(fy) * p[1] / p[2] + T(cy) - T(v)) * T(w_px);
    r[2] = (p[2] - T(z)) * T(w_z);
    return true;
  }

  double fx, fy, cx, cy, u, v, z, w_px, w_z;
};

/// The same residual for a camera rigidly attached to the pose block's: a culled keyframe's
/// observation (LocalMap::cull()) constrains its parent's pose. T_C_P = the culled keyframe's
/// camera from its parent's.
struct RgbdAttachedResidual {
  RgbdAttachedResidual(const RgbdResidual& base, const Eigen::Isometry3d& T_C_P)
      : r(base), R(T_C_P.rotation()), t(T_C_P.translation()) {}
  template <typename T>
  bool operator()(const T* pose, const T* point, T* out) const {
    // T_C_W = T_C_P * T_P_W: the parent's block composed with the fixed offset.
    T p_P[3];
    ceres::AngleAxisRotatePoint(pose, point, p_P);
    for (int i = 0; i < 3; ++i) p_P[i] += pose[3 + i];
    T p_C[3];
    for (int i = 0; i < 3; ++i) {
      p_C[i] = T(R(i, 0)) * p_P[0] + T(R(i, 1)) * p_P[1] + T(R(i, 2)) * p_P[2] + T(t[i]);
    }
    const T identity[6] = {T(0), T(0), T(0), T(0), T(0), T(0)};
    return r(identity, p_C, out);
  }
  RgbdResidual r;
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
};

/// The same residual with a fixed point (motion-only refinement).
struct RgbdPoseOnlyResidual {
  RgbdPoseOnlyResidual(const RgbdResidual& base, const Eigen::Vector3d& p_W) : r(base), p(p_W) {}
  template <typename T>
  bool operator()(const T* pose, T* out) const {
    const T point[3] = {T(p.x()), T(p.y()), T(p.z())};
    return r(pose, point, out);
  }
  RgbdResidual r;
  Eigen::Vector3d p;
};

/// The camera centre c = -R^T t of a pose block T_C_W (angle-axis[3], translation[3]).
template <typename T>
void poseBlockCentre(const T* pose, T* c) {
  const T neg_aa[3] = {-pose[0], -pose[1], -pose[2]};
  const T neg_t[3] = {-pose[3], -pose[4], -pose[5]};
  ceres::AngleAxisRotatePoint(neg_aa, neg_t, c);
}

/// Three poses in time order, dt_ab and dt_bc apart: their camera centres' acceleration
/// (finite differences of the two velocities) over sigma (m/s^2), 3 residuals.
struct AccelerationResidual {
  AccelerationResidual(double dt_ab, double dt_bc, double sigma_mps2)
      : dt_ab_(dt_ab), dt_bc_(dt_bc), scale_(1.0 / (0.5 * (dt_ab + dt_bc) * sigma_mps2)) {}
  template <typename T>
  bool operator()(const T* a, const T* b, const T* c, T* r) const {
    T ca[3], cb[3], cc[3];
    poseBlockCentre(a, ca);
    poseBlockCentre(b, cb);
    poseBlockCentre(c, cc);
    for (int i = 0; i < 3; ++i) {
      r[i] = ((cc[i] - cb[i]) / T(dt_bc_) - (cb[i] - ca[i]) / T(dt_ab_)) * T(scale_);
    }
    return true;
  }
  double dt_ab_, dt_bc_, scale_;
};

/// Isometry (camera -> world) <-> Ceres pose block T_C_W.
inline void toPoseBlock(const Eigen::Isometry3d& T_W_C, double* block) {
  const Eigen::Isometry3d T_C_W = T_W_C.inverse();
  const Eigen::AngleAxisd aa(T_C_W.rotation());
  const Eigen::Vector3d v = aa.axis() * aa.angle();
  for (int i = 0; i < 3; ++i) {
    block[i] = v[i];
    block[3 + i] = T_C_W.translation()[i];
  }
}

inline Eigen::Isometry3d fromPoseBlock(const double* block) {
  const Eigen::Vector3d v(block[0], block[1], block[2]);
  const double angle = v.norm();
  Eigen::Isometry3d T_C_W = Eigen::Isometry3d::Identity();
  if (angle > 1e-12) T_C_W.linear() = Eigen::AngleAxisd(angle, v / angle).toRotationMatrix();
  T_C_W.translation() = Eigen::Vector3d(block[3], block[4], block[5]);
  return T_C_W.inverse();
}

/// Depth std-dev model sigma_z = coeff * z^2, floored at 1 mm.
inline double depthSigma(double coeff, double z_m) { return std::max(1e-3, coeff * z_m * z_m); }

}  // namespace dynamap
