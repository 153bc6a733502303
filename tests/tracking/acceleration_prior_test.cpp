// The acceleration prior of bundle adjustment (TrackerConfig::ba_acceleration_sigma_mps2):
// keyframes made every frame while movers fill the view hold few static points each, and BA
// moves them apart; three keyframes in a row close in time keep their camera centres'
// acceleration near zero, in sigmas, without bending a motion their points do pin down.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/tracking/local_ba.hpp"

namespace dynamap::acceleration_prior_test {
namespace {

constexpr int kKeyframes = 10;
constexpr double kFrameS = 1.0 / 30.0;

/// Camera centres along a smooth path (0.3 m/s along x, a gentle curve of 1.2 m/s^2 in y).
Eigen::Isometry3d truePose(int k) {
  const double t = k * kFrameS;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.3 * t, 0.6 * t * t, 0.0);
  T.linear() = Eigen::AngleAxisd(0.2 * t, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return T;
}

struct Scene {
  int points_per_keyframe;  ///< landmarks each keyframe makes ...
  int track_length;         ///< ... seen by it and the next track_length - 1 keyframes
  double px_sigma, depth_sigma_m, pose_error_m;
};

/// A LocalMap of kKeyframes keyframes `gap_s` apart; keyframe 0 is exact, the others start
/// `pose_error_m` off. Each keyframe makes points_per_keyframe landmarks 2-3 m away (few with
/// short tracks: a view movers fill).
void buildMap(const PinholeCamera& camera, const Scene& scene, double gap_s, LocalMap& map) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(-0.8, 0.8), uy(-0.6, 0.6), uz(2.0, 3.0);
  std::normal_distribution<double> px_noise(0.0, scene.px_sigma), z_noise(0.0, scene.depth_sigma_m);
  std::normal_distribution<double> t_noise(0.0, scene.pose_error_m);
  std::vector<std::vector<std::pair<std::uint64_t, Eigen::Vector3d>>> seen(kKeyframes);
  for (int k = 0; k < kKeyframes; ++k) {
    for (int i = 0; i < scene.points_per_keyframe; ++i) {
      const Eigen::Vector3d p_W = truePose(k) * Eigen::Vector3d(ux(rng), uy(rng), uz(rng));
      const std::uint64_t id = map.addLandmark(p_W + Eigen::Vector3d(0.0, 0.0, z_noise(rng)), {});
      for (int j = k; j < std::min(kKeyframes, k + scene.track_length); ++j)
        seen[j].emplace_back(id, p_W);
    }
  }
  for (int k = 0; k < kKeyframes; ++k) {
    Eigen::Isometry3d estimate = truePose(k);
    if (k > 0) estimate.translation() += Eigen::Vector3d(t_noise(rng), t_noise(rng), t_noise(rng));
    std::vector<KeyframeObservation> obs;
    for (const auto& [id, p_W] : seen[k]) {
      const Eigen::Vector3d p_C = truePose(k).inverse() * p_W;
      obs.push_back({id, camera.project(p_C) + Eigen::Vector2d(px_noise(rng), px_noise(rng)),
                     p_C.z() + z_noise(rng)});
    }
    map.addKeyframe(k * gap_s, estimate, std::move(obs));
  }
}

struct Solved {
  double rms_error_m = 0.0;        ///< camera centres against the truth
  double rms_second_diff_m = 0.0;  ///< of the solved centres minus the true centres' (jitter)
};

Solved solve(const Scene& scene, double sigma_mps2, double gap_s = kFrameS) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  LocalMap map;
  buildMap(camera, scene, gap_s, map);
  TrackerConfig config;
  config.ba_acceleration_sigma_mps2 = sigma_mps2;
  config.ba_max_iterations = 50;
  BaWindow window = map.snapshotWindow(kKeyframes, 1, 0, 0.0);
  EXPECT_EQ(window.poses.size(), static_cast<std::size_t>(kKeyframes));
  EXPECT_TRUE(solveBundleAdjustment(camera, config, window));
  Solved s;
  std::vector<Eigen::Vector3d> err(window.poses.size());
  for (std::size_t k = 0; k < window.poses.size(); ++k) {
    err[k] = window.poses[k].translation() -
             truePose(static_cast<int>(window.keyframe_ids[k])).translation();
    s.rms_error_m += err[k].squaredNorm() / kKeyframes;
  }
  for (std::size_t k = 2; k < err.size(); ++k) {
    s.rms_second_diff_m +=
        (err[k] - 2.0 * err[k - 1] + err[k - 2]).squaredNorm() / (kKeyframes - 2);
  }
  s.rms_error_m = std::sqrt(s.rms_error_m);
  s.rms_second_diff_m = std::sqrt(s.rms_second_diff_m);
  return s;
}

// Few points, 1 px and 1.5 cm depth noise: without the prior the keyframes' centres jump by
// ~1 cm from one to the next; 5 m/s^2 is ~5 mm over two 33 ms gaps, and halves that at least.
TEST(AccelerationPrior, KeepsKeyframesInARowWithFewPointsOnASmoothPath) {
  const Scene sparse{6, 3, 1.0, 0.015, 0.01};
  const Solved without = solve(sparse, 0.0), with = solve(sparse, 5.0);
  std::cout << "second differences " << without.rms_second_diff_m << " -> "
            << with.rms_second_diff_m << " m, error " << without.rms_error_m << " -> "
            << with.rms_error_m << " m\n";
  EXPECT_GT(without.rms_second_diff_m, 0.004);  // the case the prior is for
  EXPECT_LT(with.rms_second_diff_m, 0.5 * without.rms_second_diff_m);
  EXPECT_LT(with.rms_error_m, without.rms_error_m);
}

// Many points seen by every keyframe pin the curve (1.2 m/s^2) down: the prior moves the
// solution by less than 1 mm.
TEST(AccelerationPrior, LeavesAMotionThePointsPinDownAsItIs) {
  const Scene dense{40, kKeyframes, 0.3, 0.002, 0.01};
  const Solved without = solve(dense, 0.0), with = solve(dense, 5.0);
  EXPECT_LT(without.rms_error_m, 0.005);
  EXPECT_LT(std::abs(with.rms_error_m - without.rms_error_m), 0.001);
}

// Keyframes further apart in time than ba_acceleration_max_gap_s take no prior at all.
TEST(AccelerationPrior, TakesNoPartBetweenKeyframesFarApartInTime) {
  const Scene sparse{6, 3, 1.0, 0.015, 0.01};
  const Solved without = solve(sparse, 0.0, 0.5), with = solve(sparse, 5.0, 0.5);
  EXPECT_DOUBLE_EQ(with.rms_error_m, without.rms_error_m);
}

}  // namespace
}  // namespace dynamap::acceleration_prior_test
