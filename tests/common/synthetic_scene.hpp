#pragma once

// A small ray-casting renderer of textured rectangles (planes, box faces) for tests: colour,
// depth (metres, along the optical axis) and a mask (255) of the moving boxes, from any pose.
// Header-only; seeded; ~10-20 ms per 640x480 frame.
//
//   dynamap::test::SyntheticScene scene(camera, /*seed=*/7);
//   scene.addPlane(origin, edge_u, edge_v);             // rectangle origin + two orthogonal edges
//   scene.addBox(center, half_size);                    // axis-aligned static box
//   scene.addMovingBox(center0, half_size, velocity);   // centre(t) = center0 + velocity * t
//   scene.addMovingBox(c0, h, v, /*stop_s=*/1.0);        // ... min(t, stop_s): then it stands
//   auto f = scene.render(T_W_C, t_s);                  // f.bgr, f.depth_m, f.mask

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "dynamap/core/camera.hpp"

namespace dynamap::test {

/// A camera pose in the scene: at `t`, turned `yaw_deg` about y (the rooms' down axis), then
/// `pitch_deg` about x.
inline Eigen::Isometry3d cameraPose(const Eigen::Vector3d& t, double yaw_deg, double pitch_deg) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(pitch_deg * M_PI / 180.0, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = t;
  return T;
}

struct RenderedFrame {
  cv::Mat bgr;      ///< CV_8UC3
  cv::Mat depth_m;  ///< CV_32FC1, 0 = nothing hit
  cv::Mat mask;     ///< CV_8UC1, 255 where a moving box is visible
};

class SyntheticScene {
 public:
  explicit SyntheticScene(const PinholeCamera& camera, std::uint64_t seed = 1)
      : camera_(camera), rng_(seed) {}

  /// Textured rectangle {origin + a*edge_u + b*edge_v, a,b in [0,1]}; edges orthogonal.
  void addPlane(const Eigen::Vector3d& origin, const Eigen::Vector3d& edge_u,
                const Eigen::Vector3d& edge_v) {
    addRect(origin, edge_u, edge_v, -1);
  }
  /// Axis-aligned static box.
  void addBox(const Eigen::Vector3d& center, const Eigen::Vector3d& half_size) {
    addBoxFaces(center, half_size, -1);
  }
  /// Axis-aligned box translating with constant velocity (m/s) until stop_s, standing there
  /// from then on; drawn into the mask.
  void addMovingBox(const Eigen::Vector3d& center0, const Eigen::Vector3d& half_size,
                    const Eigen::Vector3d& velocity,
                    double stop_s = std::numeric_limits<double>::infinity()) {
    velocities_.push_back(velocity);
    stops_s_.push_back(stop_s);
    addBoxFaces(center0, half_size, static_cast<int>(velocities_.size()) - 1);
  }

  /// A room (walls, floor, ceiling at 2-4 m) with two boxes, seen from the origin along +z.
  void addDefaultRoom() {
    addPlane({-2.5, -1.6, 3.5}, {5.0, 0, 0}, {0, 3.2, 0});  // back wall
    addPlane({-2.5, 1.3, 0.0}, {5.0, 0, 0}, {0, 0, 3.5});   // floor (y down)
    addPlane({-2.5, -1.6, 0.0}, {5.0, 0, 0}, {0, 0, 3.5});  // ceiling
    addPlane({-2.2, -1.6, 0.0}, {0, 0, 3.5}, {0, 3.2, 0});  // left wall
    addPlane({2.2, -1.6, 0.0}, {0, 0, 3.5}, {0, 3.2, 0});   // right wall
    addBox({-0.6, 0.8, 2.3}, {0.35, 0.5, 0.35});
    addBox({0.7, 0.5, 2.0}, {0.25, 0.8, 0.25});
  }

  RenderedFrame render(const Eigen::Isometry3d& T_W_C, double t_s) const {
    RenderedFrame f;
    f.bgr = cv::Mat(camera_.height, camera_.width, CV_8UC3, cv::Scalar(0, 0, 0));
    f.depth_m = cv::Mat(camera_.height, camera_.width, CV_32FC1, cv::Scalar(0.f));
    f.mask = cv::Mat(camera_.height, camera_.width, CV_8UC1, cv::Scalar(0));
    const Eigen::Isometry3d T_C_W = T_W_C.inverse();
    for (const Rect& r : rects_) drawRect(r, T_C_W, t_s, f);
    return f;
  }

  const PinholeCamera& camera() const { return camera_; }

 private:
  static constexpr double kNearM = 0.05;  ///< nearer surfaces are not drawn

  struct Rect {
    Eigen::Vector3d origin, edge_u, edge_v;
    cv::Mat texture;  // CV_8UC3
    int moving = -1;  // index into velocities_, -1 = static
  };

  void addBoxFaces(const Eigen::Vector3d& c, const Eigen::Vector3d& h, int moving) {
    const Eigen::Vector3d ex(2 * h.x(), 0, 0), ey(0, 2 * h.y(), 0), ez(0, 0, 2 * h.z());
    const Eigen::Vector3d lo = c - h;
    addRect(lo, ex, ey, moving);
    addRect(lo + ez, ex, ey, moving);
    addRect(lo, ez, ey, moving);
    addRect(lo + ex, ez, ey, moving);
    addRect(lo, ex, ez, moving);
    addRect(lo + ey, ex, ez, moving);
  }

  void addRect(const Eigen::Vector3d& o, const Eigen::Vector3d& eu, const Eigen::Vector3d& ev,
               int moving) {
    constexpr double kTexelsPerMetre = 250.0;
    const int w = std::clamp(static_cast<int>(eu.norm() * kTexelsPerMetre), 16, 1400);
    const int h = std::clamp(static_cast<int>(ev.norm() * kTexelsPerMetre), 16, 1400);
    rects_.push_back(Rect{o, eu, ev, makeTexture(w, h), moving});
  }

  /// Random blobs and bars on a random base colour, slightly blurred: corners at many scales.
  cv::Mat makeTexture(int w, int h) {
    cv::Mat tex(h, w, CV_8UC3, randomColor());
    const int count = w * h / 60;
    for (int i = 0; i < count; ++i) {
      const cv::Point c(rng_.uniform(0, w), rng_.uniform(0, h));
      const int s = rng_.uniform(2, 12);
      if (rng_.uniform(0, 2) == 0) {
        cv::circle(tex, c, s, randomColor(), cv::FILLED, cv::LINE_AA);
      } else {
        cv::rectangle(tex, c, c + cv::Point(rng_.uniform(2, 16), rng_.uniform(2, 16)),
                      randomColor(), cv::FILLED);
      }
    }
    cv::GaussianBlur(tex, tex, cv::Size(3, 3), 0.8);
    return tex;
  }
  cv::Scalar randomColor() {
    return cv::Scalar(rng_.uniform(20, 236), rng_.uniform(20, 236), rng_.uniform(20, 236));
  }

  void drawRect(const Rect& r, const Eigen::Isometry3d& T_C_W, double t_s, RenderedFrame& f) const {
    Eigen::Vector3d shift = Eigen::Vector3d::Zero();
    if (r.moving >= 0) {
      const auto k = static_cast<std::size_t>(r.moving);
      shift = velocities_[k] * std::min(t_s, stops_s_[k]);
    }
    const Eigen::Vector3d o = T_C_W * (r.origin + shift);
    const Eigen::Vector3d eu = T_C_W.linear() * r.edge_u;
    const Eigen::Vector3d ev = T_C_W.linear() * r.edge_v;
    const Eigen::Vector3d n = eu.cross(ev);
    const double inv_uu = 1.0 / eu.squaredNorm(), inv_vv = 1.0 / ev.squaredNorm();
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    if (!pixelBounds({o, o + eu, o + eu + ev, o + ev}, x0, y0, x1, y1)) return;
    const double n_dot_o = n.dot(o);
    const int tw = r.texture.cols, th = r.texture.rows;
    // Rows are independent: render them in parallel.
    cv::parallel_for_(cv::Range(y0, y1 + 1), [&](const cv::Range& rows) {
      for (int y = rows.start; y < rows.end; ++y) {
        const double dy = (y - camera_.cy) / camera_.fy;
        auto* bgr = f.bgr.ptr<cv::Vec3b>(y);
        auto* depth = f.depth_m.ptr<float>(y);
        auto* mask = f.mask.ptr<std::uint8_t>(y);
        for (int x = x0; x <= x1; ++x) {
          const Eigen::Vector3d d((x - camera_.cx) / camera_.fx, dy, 1.0);
          const double denom = n.dot(d);
          if (std::abs(denom) < 1e-12) continue;
          const double z = n_dot_o / denom;
          if (z < kNearM || (depth[x] > 0.f && z >= depth[x])) continue;
          const Eigen::Vector3d p = z * d - o;
          const double a = p.dot(eu) * inv_uu, b = p.dot(ev) * inv_vv;
          if (a < 0.0 || a > 1.0 || b < 0.0 || b > 1.0) continue;
          depth[x] = static_cast<float>(z);
          bgr[x] = sample(r.texture, a * (tw - 1), b * (th - 1));
          mask[x] = r.moving >= 0 ? 255 : 0;
        }
      }
    });
  }

  /// Pixel bounding box (x0..x1, y0..y1, inside the image, one pixel of margin) of the convex
  /// polygon `corners` (camera frame) clipped to z >= kNearM; false when none of it is in front.
  /// A rectangle reaching behind the camera is bounded by its visible part, not by the whole
  /// image (a room around the camera: most of its walls reach behind it).
  bool pixelBounds(const std::array<Eigen::Vector3d, 4>& corners, int& x0, int& y0, int& x1,
                   int& y1) const {
    std::vector<Eigen::Vector3d> front;
    for (std::size_t i = 0; i < corners.size(); ++i) {
      const Eigen::Vector3d& a = corners[i];
      const Eigen::Vector3d& b = corners[(i + 1) % corners.size()];
      if (a.z() >= kNearM) front.push_back(a);
      if ((a.z() >= kNearM) != (b.z() >= kNearM)) {
        front.push_back(a + (b - a) * ((kNearM - a.z()) / (b.z() - a.z())));
      }
    }
    if (front.empty()) return false;
    double minx = 1e9, miny = 1e9, maxx = -1e9, maxy = -1e9;
    for (const auto& c : front) {
      const Eigen::Vector2d uv = camera_.project(c);
      minx = std::min(minx, uv.x()), maxx = std::max(maxx, uv.x());
      miny = std::min(miny, uv.y()), maxy = std::max(maxy, uv.y());
    }
    const auto clampTo = [](double v, int hi) {
      return static_cast<int>(std::clamp(v, -1.0, static_cast<double>(hi) + 1.0));
    };
    x0 = std::max(0, clampTo(std::floor(minx), camera_.width) - 1);
    y0 = std::max(0, clampTo(std::floor(miny), camera_.height) - 1);
    x1 = std::min(camera_.width - 1, clampTo(std::ceil(maxx), camera_.width) + 1);
    y1 = std::min(camera_.height - 1, clampTo(std::ceil(maxy), camera_.height) + 1);
    return x0 <= x1 && y0 <= y1;
  }

  static cv::Vec3b sample(const cv::Mat& tex, double u, double v) {
    const int x = std::min(static_cast<int>(u), tex.cols - 2);
    const int y = std::min(static_cast<int>(v), tex.rows - 2);
    const double fx = u - x, fy = v - y;
    const cv::Vec3b* r0 = tex.ptr<cv::Vec3b>(y);
    const cv::Vec3b* r1 = tex.ptr<cv::Vec3b>(y + 1);
    cv::Vec3b out;
    for (int c = 0; c < 3; ++c) {
      const double top = r0[x][c] * (1 - fx) + r0[x + 1][c] * fx;
      const double bot = r1[x][c] * (1 - fx) + r1[x + 1][c] * fx;
      out[c] = static_cast<std::uint8_t>(top * (1 - fy) + bot * fy + 0.5);
    }
    return out;
  }

  PinholeCamera camera_;
  cv::RNG rng_;
  std::vector<Rect> rects_;
  std::vector<Eigen::Vector3d> velocities_;
  std::vector<double> stops_s_;
};

}  // namespace dynamap::test
