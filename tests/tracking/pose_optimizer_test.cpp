#include <gtest/gtest.h>

#include <random>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/tracking/pose_optimizer.hpp"

namespace dynamap {
namespace {

TEST(PoseOptimizer, RecoversKnownPoseWithThirtyPercentOutliers) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  TrackerConfig config;
  const PoseOptimizer optimizer(camera, config);
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> ux(0.0, camera.width), uy(0.0, camera.height);
  std::uniform_real_distribution<double> uz(0.8, 4.0);
  std::normal_distribution<double> px_noise(0.0, 0.3);

  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  T_W_C.linear() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1.0, -0.1).normalized()).toRotationMatrix();
  T_W_C.translation() = Eigen::Vector3d(0.4, -0.2, 1.1);

  constexpr int kPoints = 300;
  std::vector<PoseCorrespondence> corr;
  std::vector<bool> outlier;
  for (int i = 0; i < kPoints; ++i) {
    const double u = ux(rng), v = uy(rng), z = uz(rng);
    PoseCorrespondence c;
    c.p_W = T_W_C * camera.backProject(u, v, z);
    std::normal_distribution<double> z_noise(0.0, 0.5 * config.depth_sigma_coeff * z * z);
    c.px = Eigen::Vector2d(u + px_noise(rng), v + px_noise(rng));
    c.depth_m = z + z_noise(rng);
    const bool bad = i % 10 < 3;  // 30 % gross outliers: wrong pixel and depth
    if (bad) {
      c.px = Eigen::Vector2d(ux(rng), uy(rng));
      c.depth_m = uz(rng);
    }
    corr.push_back(c);
    outlier.push_back(bad);
  }
  Eigen::Isometry3d guess = T_W_C;
  guess.translation() += Eigen::Vector3d(0.05, -0.03, 0.04);
  guess.linear() =
      guess.linear() * Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()).toRotationMatrix();

  const PoseEstimate est = optimizer.estimate(corr, guess, nullptr);
  ASSERT_TRUE(est.ok);
  const Eigen::Isometry3d err = T_W_C.inverse() * est.T_W_C;
  EXPECT_LT(err.translation().norm(), 0.005);
  EXPECT_LT(Eigen::AngleAxisd(err.rotation()).angle() * 180.0 / M_PI, 0.2);
  int outliers_accepted = 0, inliers_kept = 0;
  for (int i = 0; i < kPoints; ++i) {
    if (est.inlier[static_cast<std::size_t>(i)])
      (outlier[static_cast<std::size_t>(i)] ? outliers_accepted : inliers_kept)++;
  }
  EXPECT_LE(outliers_accepted, 3);
  EXPECT_GE(inliers_kept, 190);  // of 210 true inliers (95 % chi-square gate)
}

}  // namespace
}  // namespace dynamap
