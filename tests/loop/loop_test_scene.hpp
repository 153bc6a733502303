#pragma once

// Helpers of the loop-closure tests: keyframes as the tracker would hand them to LoopCloser
// (gridded ORB keypoints, depth sampled at them with noise, static = outside the movers' mask),
// and z-buffered composition of several synthetic scenes (the same seed gives the same texture,
// so a patch can be repeated at another place of the world).

#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "dynamap/core/tracking/depth_sampling.hpp"
#include "dynamap/core/tracking/feature_extractor.hpp"
#include "dynamap/core/tracking/loop_closer.hpp"
#include "synthetic_scene.hpp"

namespace dynamap::test {

/// A 6 x 6 m room (walls of 2 m panels, each its own texture) with boxes along the walls.
inline void addLoopRoom(test::SyntheticScene& scene) {
  for (int i = 0; i < 3; ++i) {
    const double a = -3.0 + 2.0 * i;
    scene.addPlane({a, -1.5, 3.0}, {2.0, 0, 0}, {0, 3.0, 0});    // far wall (+z)
    scene.addPlane({a, -1.5, -3.0}, {2.0, 0, 0}, {0, 3.0, 0});   // near wall (-z)
    scene.addPlane({-3.0, -1.5, a}, {0, 0, 2.0}, {0, 3.0, 0});   // left wall (-x)
    scene.addPlane({3.0, -1.5, a}, {0, 0, 2.0}, {0, 3.0, 0});    // right wall (+x)
    scene.addPlane({a, 1.5, -3.0}, {2.0, 0, 0}, {0, 0, 6.0});    // floor strip (y down)
  }
  scene.addBox({2.2, 0.9, 1.0}, {0.4, 0.6, 0.4});
  scene.addBox({-2.3, 1.0, -1.2}, {0.3, 0.5, 0.5});
  scene.addBox({0.8, 1.1, -2.3}, {0.5, 0.4, 0.3});
  scene.addBox({-1.0, 0.8, 2.4}, {0.3, 0.7, 0.3});
}

/// Nearest surface of all `scenes` at each pixel.
inline RenderedFrame renderComposite(const std::vector<const SyntheticScene*>& scenes,
                                     const Eigen::Isometry3d& T_W_C, double t_s) {
  RenderedFrame out = scenes.front()->render(T_W_C, t_s);
  for (std::size_t s = 1; s < scenes.size(); ++s) {
    const RenderedFrame f = scenes[s]->render(T_W_C, t_s);
    for (int y = 0; y < out.depth_m.rows; ++y) {
      for (int x = 0; x < out.depth_m.cols; ++x) {
        const float z = f.depth_m.at<float>(y, x), z_out = out.depth_m.at<float>(y, x);
        if (z > 0.f && (z_out <= 0.f || z < z_out)) {
          out.depth_m.at<float>(y, x) = z;
          out.bgr.at<cv::Vec3b>(y, x) = f.bgr.at<cv::Vec3b>(y, x);
          out.mask.at<std::uint8_t>(y, x) = f.mask.at<std::uint8_t>(y, x);
        }
      }
    }
  }
  return out;
}

/// The keyframe of `frame` at the (drifted) estimate `T_W_C_est`; depth noise 0.3 % of depth
/// (seeded by `rng`); `use_mask` false flags every keypoint static (movers included).
inline LoopKeyframeInput makeLoopKeyframe(std::uint64_t id, const RenderedFrame& frame,
                                          const Eigen::Isometry3d& T_W_C_est,
                                          const GridOrbExtractor& orb, const TrackerConfig& config,
                                          bool use_mask, std::mt19937& rng) {
  cv::Mat gray;
  cv::cvtColor(frame.bgr, gray, cv::COLOR_BGR2GRAY);
  const OrbFeatures features = orb.extract(gray, cv::Mat(), {});
  std::normal_distribution<double> noise(0.0, 1.0);
  LoopKeyframeInput kf;
  kf.id = id;
  kf.T_W_C = T_W_C_est;
  kf.keypoints = features.keypoints;
  kf.descriptors = features.descriptors;
  for (const cv::KeyPoint& k : features.keypoints) {
    double z = sampleDepth(frame.depth_m, k.pt.x, k.pt.y, config.depth_min_m,
                           config.landmark_depth_max_m);
    if (z > 0.0) z *= 1.0 + 0.003 * noise(rng);
    kf.depth_m.push_back(z);
    const bool moving = frame.mask.at<std::uint8_t>(cvRound(k.pt.y), cvRound(k.pt.x)) != 0;
    kf.is_static.push_back(use_mask && moving ? 0 : 1);
  }
  return kf;
}

/// Small rotation (radians, about x, y, z) and translation (metres) as a pose.
inline Eigen::Isometry3d smallMotion(const Eigen::Vector3d& rot_rad, const Eigen::Vector3d& t_m) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (rot_rad.norm() > 0.0) {
    T.linear() = Eigen::AngleAxisd(rot_rad.norm(), rot_rad.normalized()).toRotationMatrix();
  }
  T.translation() = t_m;
  return T;
}

/// The camera on the loop room's circle (1 m from the centre) at `yaw_deg`, looking outward.
inline Eigen::Isometry3d circlePose(double yaw_deg) {
  const double rad = yaw_deg * M_PI / 180.0;
  return cameraPose({std::sin(rad), 0.0, std::cos(rad)}, yaw_deg, 0.0);
}

/// Keyframe k of the loop room's circle: 7.5 k deg of yaw (48 keyframes a round).
inline Eigen::Isometry3d circleKeyframePose(int k) { return circlePose(7.5 * k); }

/// Odometry from `from` to `to` as a drifting tracker measures it: 0.3 deg of yaw and 0.1 deg of
/// pitch too much per step, plus noise (0.05 deg, 5 mm; seeded by `rng`).
inline Eigen::Isometry3d driftingStep(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to,
                                      std::mt19937& rng) {
  constexpr double kDeg = M_PI / 180.0;
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d rot(0.1 * kDeg + 0.05 * kDeg * n(rng), 0.3 * kDeg, 0.05 * kDeg * n(rng));
  const Eigen::Vector3d t(0.005 * n(rng), 0.005 * n(rng), 0.005 * n(rng));
  return from.inverse() * to * smallMotion(rot, t);
}

inline double rotationDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / M_PI;
}

}  // namespace dynamap::test
