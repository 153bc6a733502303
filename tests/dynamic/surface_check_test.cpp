// An object's whole surface against itself a few frames back (checkSurface()): hundreds of
// depths give a median that a still person keeps within millimetres although each depth is
// centimetres off, while a sway along the line of sight moves it.
#include <cmath>

#include <gtest/gtest.h>

#include "dynamap/core/dynamic/depth_check.hpp"
#include "dynamap/core/dynamic/region_fusion.hpp"
#include "fusion_point_grid.hpp"

namespace dynamap::surface_check_test {
namespace {

const cv::Vec4d kK(535.4, 539.2, 320.1, 247.6);
const cv::Rect& kPerson = test::kStillPerson;

/// A wall 5 m away with a person-sized patch at `z` m, each pixel off by the Kinect's noise at
/// its depth (depthNoiseM) drawn from `rng`.
cv::Mat noisyDepth(double z, cv::RNG& rng) {
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(5.f));
  depth(kPerson).setTo(static_cast<float>(z));
  cv::Mat noise(depth.size(), CV_32F);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
  cv::Mat sigma(depth.size(), CV_32F, cv::Scalar(static_cast<float>(depthNoiseM(5.0))));
  sigma(kPerson).setTo(static_cast<float>(depthNoiseM(z)));
  return depth + noise.mul(sigma);
}

cv::Mat personRegion() {
  cv::Mat region = cv::Mat::zeros(480, 640, CV_8UC1);
  region(kPerson).setTo(255);
  return region;
}

TEST(SurfaceCheck, ANoisyStillSurfaceStaysWithinMillimetresAMovedOneShowsItsDepthChange) {
  cv::RNG rng(7);
  const cv::Matx44d T = cv::Matx44d::eye();
  const std::vector<cv::Vec3f> before =
      sampleSurface(personRegion(), noisyDepth(3.0, rng), T, kK, 8);
  ASSERT_GT(before.size(), 300u);
  AnchorCheck still, moved, hidden;
  checkSurface(before, personRegion(), noisyDepth(3.0, rng), T, kK, 0.15, &still);
  EXPECT_GT(still.surface_points, 300);
  // Each depth is 1.4 cm off (one sigma at 3 m), twice over; their median is not.
  EXPECT_LT(std::abs(still.surface_dz_m), 0.003);
  checkSurface(before, personRegion(), noisyDepth(3.02, rng), T, kK, 0.15, &moved);
  EXPECT_NEAR(moved.surface_dz_m, 0.02, 0.003);
  // Where the object's pixels are not (hidden now), its old points are not compared.
  cv::Mat half = personRegion();
  half(cv::Rect(kPerson.x, kPerson.y, kPerson.width / 2, kPerson.height)).setTo(0);
  checkSurface(before, half, noisyDepth(3.0, rng), T, kK, 0.15, &hidden);
  EXPECT_LT(hidden.surface_points, still.surface_points * 0.6);
  EXPECT_GT(hidden.surface_points, still.surface_points * 0.4);
}

/// Share of frames in which a person at depth z(i) (noisy, as above) is kept.
template <typename DepthOf>
double keptShare(const DynamicConfig& c, int frames, DepthOf z) {
  cv::RNG rng(11);
  return test::keptShare(
      c, frames, [&](int i) { return noisyDepth(z(i), rng); }, true);
}

TEST(FusionSurface, ASwayAlongTheLineOfSightWithinTheAnchorsDepthNoiseIsSeenAStillPersonKept) {
  // 3 m away, 3 cm amplitude towards the camera, 2.5 s period (75 frames), three periods:
  // the anchored points' depths (each 1.4 cm off) stay within their 3 cm limit most of the time.
  const auto sway = [](int i) { return 3.0 + 0.03 * std::sin(2.0 * CV_PI * i / 75.0); };
  const auto stand = [](int) { return 3.0; };
  DynamicConfig c;
  const double swayer = keptShare(c, 225, sway);
  const double still = keptShare(c, 225, stand);
  c.static_surface_m = 0.0;
  const double swayer_points_only = keptShare(c, 225, sway);
  const double still_points_only = keptShare(c, 225, stand);
  EXPECT_GT(still, 0.9);
  EXPECT_GT(still_points_only, 0.9);
  EXPECT_LT(swayer, 0.3) << swayer_points_only;
  EXPECT_GT(swayer_points_only, swayer + 0.3) << swayer;
}

}  // namespace
}  // namespace dynamap::surface_check_test
