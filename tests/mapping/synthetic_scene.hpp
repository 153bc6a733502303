#pragma once

// A synthetic room for the mapping tests: floor z = 0 and two walls (x = 2, y = 2) bounded to
// [-2, 2], a static box on the floor, and a floating box that moves between frames (marked 255
// in the dynamic mask). Depth, colour and mask are rendered exactly by ray casting.

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"

namespace dynamap::test {

struct Box {
  Eigen::Vector3d lo, hi;
  double distance(const Eigen::Vector3d& p) const {  // to the box surface
    const Eigen::Vector3d d = (lo - p).cwiseMax(p - hi);
    const double outside = d.cwiseMax(0.0).norm();
    const double inside = std::min(d.maxCoeff(), 0.0);
    return outside > 0 ? outside : -inside;
  }
  bool contains(const Eigen::Vector3d& p, double margin) const {
    return (p.array() >= lo.array() - margin).all() && (p.array() <= hi.array() + margin).all();
  }
  // Ray (o + t d) entry distance, or infinity.
  double intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
    double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      const double inv = 1.0 / d[a];
      double ta = (lo[a] - o[a]) * inv, tb = (hi[a] - o[a]) * inv;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    return t0 <= t1 && t0 > 0 ? t0 : std::numeric_limits<double>::infinity();
  }
};

struct SyntheticFrame {
  Eigen::Isometry3d T_W_C;
  cv::Mat bgr, depth_m, mask;
  Box moving;
};

class SyntheticScene {
 public:
  static constexpr double kHalf = 2.0;
  Box static_box{{0.3, -0.2, 0.0}, {0.7, 0.2, 0.4}};

  static PinholeCamera camera() {
    PinholeCamera c;
    c.width = 160;
    c.height = 120;
    c.fx = c.fy = 110.0;
    c.cx = 79.5;
    c.cy = 59.5;
    return c;
  }
  /// Distance from p to the static geometry (offset by `shift` when the map was moved).
  double staticDistance(const Eigen::Vector3d& p_in,
                        const Eigen::Vector3d& shift = Eigen::Vector3d::Zero()) const {
    const Eigen::Vector3d p = p_in - shift;
    auto clampOut = [](double v) { return std::max(0.0, std::fabs(v) - kHalf); };
    const double floor = std::hypot(std::fabs(p.z()), std::hypot(clampOut(p.x()), clampOut(p.y())));
    const double wall_x =
        std::hypot(std::fabs(p.x() - kHalf), std::hypot(clampOut(p.y()), std::max(0.0, -p.z())));
    const double wall_y =
        std::hypot(std::fabs(p.y() - kHalf), std::hypot(clampOut(p.x()), std::max(0.0, -p.z())));
    return std::min({floor, wall_x, wall_y, static_box.distance(p)});
  }
  /// The moving box in frame k.
  static Box movingBox(int k) {
    const double x = -0.2 + 0.2 * k;
    return Box{{x, 0.9, 0.4}, {x + 0.3, 1.2, 1.3}};
  }
  /// Camera k of n on an arc, looking at the room centre.
  static Eigen::Isometry3d pose(int k, int n) {
    const double a = -2.6 + 0.5 * k / std::max(1, n - 1);
    const Eigen::Vector3d eye(1.9 * std::cos(a), 1.9 * std::sin(a), 1.3);
    const Eigen::Vector3d target(0.6, 0.6, 0.4);
    const Eigen::Vector3d z = (target - eye).normalized();
    const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d y = z.cross(x);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear().col(0) = x;
    T.linear().col(1) = y;
    T.linear().col(2) = z;
    T.translation() = eye;
    return T;
  }

  /// `hidden` moved `share` of the way towards camera k of n and shrunk with it (bounding box of
  /// its corners): a box that hides `hidden` from that camera and little else.
  static Box occluderFor(int k, int n, const Box& hidden, double share = 0.5) {
    const Eigen::Vector3d eye = pose(k, n).translation();
    Box b{Eigen::Vector3d::Constant(1e9), Eigen::Vector3d::Constant(-1e9)};
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d corner((c & 1) ? hidden.hi.x() : hidden.lo.x(),
                                   (c & 2) ? hidden.hi.y() : hidden.lo.y(),
                                   (c & 4) ? hidden.hi.z() : hidden.lo.z());
      const Eigen::Vector3d p = eye + (1.0 - share) * (corner - eye);
      b.lo = b.lo.cwiseMin(p), b.hi = b.hi.cwiseMax(p);
    }
    return b;
  }

  SyntheticFrame render(int k, int n) const { return render(k, n, movingBox(k)); }
  /// Frame k with the moving box wherever the caller puts it.
  SyntheticFrame render(int k, int n, const Box& moving) const {
    const PinholeCamera cam = camera();
    SyntheticFrame f;
    f.T_W_C = pose(k, n);
    f.moving = moving;
    f.depth_m = cv::Mat::zeros(cam.height, cam.width, CV_32FC1);
    f.bgr = cv::Mat::zeros(cam.height, cam.width, CV_8UC3);
    f.mask = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
    const Eigen::Vector3d o = f.T_W_C.translation();
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        const Eigen::Vector3d d_C((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
        const Eigen::Vector3d d = f.T_W_C.linear() * d_C;  // t along d = depth
        double best = std::numeric_limits<double>::infinity();
        int what = 0;
        auto plane = [&](int axis, double value, int id) {
          const double t = (value - o[axis]) / d[axis];
          if (!(t > 0) || t >= best) return;
          const Eigen::Vector3d p = o + t * d;
          for (int a = 0; a < 3; ++a) {
            if (a != axis && (p[a] < -kHalf - 1e-9 || p[a] > kHalf + 1e-9)) return;
            if (a == 2 && p[a] < 0) return;
          }
          best = t;
          what = id;
        };
        plane(2, 0.0, 1);
        plane(0, kHalf, 2);
        plane(1, kHalf, 3);
        if (const double t = static_box.intersect(o, d); t < best) best = t, what = 4;
        if (const double t = f.moving.intersect(o, d); t < best) best = t, what = 5;
        if (what == 0 || best > 6.0) continue;
        f.depth_m.at<float>(v, u) = static_cast<float>(best);
        f.bgr.at<cv::Vec3b>(v, u) = cv::Vec3b(40 * what, 255 - 40 * what, 128);
        if (what == 5) f.mask.at<std::uint8_t>(v, u) = 255;
      }
    }
    return f;
  }
};

}  // namespace dynamap::test
