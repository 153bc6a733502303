#include <gtest/gtest.h>

#include "dynamap/mapping/held_revision.hpp"

namespace dynamap {
namespace {

constexpr double kPersonDepthM = 2.0;  // a flat person 2 m in front of keyframe 0
constexpr double kWallDepthM = 3.5;

Eigen::Isometry3d shiftedX(double x_m) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation().x() = x_m;
  return T;
}

/// A keyframe at `T_W_C` seeing a wall at z = kWallDepthM (world) and, in front of it, a
/// 0.5 x 1.5 m person at z = kPersonDepthM (world x in [-0.25, 0.25]). The person's pixels are
/// `held` or `confirmed` as asked.
HeldKeyframe view(const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C, bool held,
                  bool confirmed) {
  HeldKeyframe kf;
  kf.T_W_C = T_W_C;
  kf.depth_m = cv::Mat(camera.height, camera.width, CV_32FC1, cv::Scalar(0));
  cv::Mat person = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      // Ray through (u, v) in the world (the poses only translate).
      const Eigen::Vector3d dir((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
      const Eigen::Vector3d at = T_W_C.translation() + dir * kPersonDepthM;
      const bool on_person = std::abs(at.x()) < 0.25 && std::abs(at.y()) < 0.75;
      kf.depth_m.at<float>(v, u) = static_cast<float>(on_person ? kPersonDepthM : kWallDepthM);
      if (on_person) person.at<std::uint8_t>(v, u) = 255;
    }
  }
  if (held) kf.held = person;
  if (confirmed) kf.confirmed_C = maskPoints(camera, kf.depth_m, person, 4);
  return kf;
}

TEST(HeldRevision, HeldPixelsOtherKeyframesConfirmedStaticMoreOftenThanMovingAreFound) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  std::vector<HeldKeyframe> kfs;
  kfs.push_back(view(camera, shiftedX(0.0), /*held=*/true, /*confirmed=*/false));
  kfs.push_back(view(camera, shiftedX(0.1), false, true));
  kfs.push_back(view(camera, shiftedX(0.2), false, true));
  const int person_px = cv::countNonZero(kfs[0].held);
  ASSERT_GT(person_px, 10000);

  // Two other keyframes confirmed him where keyframe 0 held him back: all of him is found.
  auto hits = heldConfirmedElsewhere(camera, kfs, 0.03, 2);
  ASSERT_FALSE(hits[0].empty());
  EXPECT_GT(cv::countNonZero(hits[0] & kfs[0].held), 0.95 * person_px);
  EXPECT_EQ(cv::countNonZero(hits[0] & ~kfs[0].held), 0);  // only held pixels
  EXPECT_TRUE(hits[1].empty() && hits[2].empty());         // nothing held there

  // One confirming keyframe is not enough when two are asked for.
  kfs.pop_back();
  EXPECT_TRUE(heldConfirmedElsewhere(camera, kfs, 0.03, 2)[0].empty());
  EXPECT_FALSE(heldConfirmedElsewhere(camera, kfs, 0.03, 1)[0].empty());

  // Its own confirmation does not count, and a person confirmed 0.8 m to the side is someone else.
  std::vector<HeldKeyframe> self{view(camera, shiftedX(0.0), true, true)};
  EXPECT_TRUE(heldConfirmedElsewhere(camera, self, 0.03, 1)[0].empty());
  std::vector<HeldKeyframe> apart{view(camera, shiftedX(0.0), true, false),
                                  view(camera, shiftedX(0.0), false, true),
                                  view(camera, shiftedX(0.0), false, true)};
  for (std::size_t k = 1; k < apart.size(); ++k) {
    for (auto& p : apart[k].confirmed_C) p.x() += 0.8f;
  }
  EXPECT_TRUE(heldConfirmedElsewhere(camera, apart, 0.03, 2)[0].empty());

  // Confirmed static by two keyframes but seen moving there by three (a swayer, or walkers
  // crossing the spot): no standing person.
  std::vector<HeldKeyframe> swayer{view(camera, shiftedX(0.0), true, false),
                                   view(camera, shiftedX(0.1), false, true),
                                   view(camera, shiftedX(0.2), false, true)};
  for (int k = 0; k < 3; ++k) {
    HeldKeyframe moved = view(camera, shiftedX(0.05 * k), false, true);
    moved.moved_C = moved.confirmed_C;
    moved.confirmed_C.clear();
    swayer.push_back(moved);
  }
  EXPECT_TRUE(heldConfirmedElsewhere(camera, swayer, 0.03, 2)[0].empty());
  swayer.pop_back();  // two moving, two confirming: still not more confirmed than moved
  EXPECT_TRUE(heldConfirmedElsewhere(camera, swayer, 0.03, 2)[0].empty());
  swayer.pop_back();  // one moving, two confirming
  EXPECT_FALSE(heldConfirmedElsewhere(camera, swayer, 0.03, 2)[0].empty());
}

}  // namespace
}  // namespace dynamap
