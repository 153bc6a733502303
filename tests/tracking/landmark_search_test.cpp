#include <gtest/gtest.h>

#include <random>

#include "dynamap/core/tracking/landmark_search.hpp"

namespace dynamap {
namespace {

cv::Mat randomDescriptor(std::mt19937& rng) {
  cv::Mat d(1, 32, CV_8U);
  for (int i = 0; i < 32; ++i) d.at<std::uint8_t>(0, i) = static_cast<std::uint8_t>(rng() & 0xff);
  return d;
}

/// `bits` flipped bits of `d` (Hamming distance exactly `bits`).
cv::Mat flipBits(const cv::Mat& d, int bits) {
  cv::Mat out = d.clone();
  for (int b = 0; b < bits; ++b)
    out.at<std::uint8_t>(0, b / 8) ^= static_cast<std::uint8_t>(1 << (b % 8));
  return out;
}

struct Scene {
  PinholeCamera camera = cameraPreset("freiburg3");
  OrbFeatures features;
  std::vector<double> depth;
  LandmarkCandidates candidates;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();

  /// A landmark at pixel (u, v) and depth z, and a keypoint `offset_px` to its right with depth
  /// `kp_depth` and a descriptor `bits` away from the landmark's.
  void add(std::mt19937& rng, double u, double v, double z, double offset_px, double kp_depth,
           int bits) {
    const cv::Mat d = randomDescriptor(rng);
    candidates.ids.push_back(100 + candidates.ids.size());
    candidates.descriptors.push_back(d);
    candidates.points.push_back(T_W_C * camera.backProject(u, v, z));
    features.keypoints.emplace_back(static_cast<float>(u + offset_px), static_cast<float>(v), 7.f);
    features.descriptors.push_back(flipBits(d, bits));
    depth.push_back(kp_depth);
  }
};

TEST(LandmarkSearch, MatchesNearProjectionsAndRejectsFarDeepOrUnlikeKeypoints) {
  std::mt19937 rng(3);
  Scene s;
  s.T_W_C.translation() = Eigen::Vector3d(0.3, -0.1, 0.2);
  s.T_W_C.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  s.add(rng, 100, 100, 2.0, 3.0, 2.02, 10);  // 0: close, depth within 5 %, similar -> match
  s.add(rng, 300, 100, 2.0, 25.0, 2.0, 5);   // 1: 25 px from its projection -> no match
  s.add(rng, 500, 100, 2.0, 2.0, 1.5, 5);    // 2: depth 25 % off (something in front) -> none
  s.add(rng, 100, 300, 2.0, 2.0, 2.0, 90);   // 3: descriptor too different -> none
  s.add(rng, 300, 300, 2.0, 4.0, 0.0, 20);   // 4: no measured depth -> match on image alone
  const auto match = searchByProjection(s.features, s.depth, s.candidates, s.T_W_C, s.camera,
                                        LandmarkSearchParams{});
  ASSERT_EQ(match.size(), 5u);
  EXPECT_EQ(match[0], 0);
  EXPECT_EQ(match[1], -1);
  EXPECT_EQ(match[2], -1);
  EXPECT_EQ(match[3], -1);
  EXPECT_EQ(match[4], 4);
}

TEST(LandmarkSearch, AmbiguousNeighboursFailTheRatioTestAndEachLandmarkIsUsedOnce) {
  std::mt19937 rng(5);
  Scene s;
  s.add(rng, 200, 200, 1.5, 1.0, 1.5, 12);
  // A second keypoint beside the first with an equally close descriptor: ambiguous.
  s.features.keypoints.emplace_back(203.f, 200.f, 7.f);
  s.features.descriptors.push_back(flipBits(s.candidates.descriptors.row(0), 13));
  s.depth.push_back(1.5);
  auto match = searchByProjection(s.features, s.depth, s.candidates, s.T_W_C, s.camera, {});
  EXPECT_EQ(match[0], -1);
  EXPECT_EQ(match[1], -1);
  // A clearly better one wins, the other keypoint stays free.
  cv::Mat row = s.features.descriptors.row(1);
  flipBits(s.candidates.descriptors.row(0), 2).copyTo(row);
  match = searchByProjection(s.features, s.depth, s.candidates, s.T_W_C, s.camera, {});
  EXPECT_EQ(match[0], -1);
  EXPECT_EQ(match[1], 0);
}

TEST(LandmarkSearch, LandmarksBehindTheCameraOrOutsideTheImageAreSkipped) {
  std::mt19937 rng(9);
  Scene s;
  s.add(rng, 320, 240, 2.0, 0.0, 2.0, 0);
  s.candidates.points[0] = Eigen::Vector3d(0.0, 0.0, -2.0);  // behind
  s.add(rng, 320, 240, 2.0, 0.0, 2.0, 0);
  s.candidates.points[1] = Eigen::Vector3d(50.0, 0.0, 2.0);  // far outside the image
  const auto match = searchByProjection(s.features, s.depth, s.candidates, s.T_W_C, s.camera, {});
  EXPECT_EQ(match[0], -1);
  EXPECT_EQ(match[1], -1);
}

TEST(LandmarkSearch, CandidatesAreFilteredByIdKeepingTheirRowsTogether) {
  std::mt19937 rng(11);
  Scene s;
  for (int i = 0; i < 5; ++i) s.add(rng, 100 + 50 * i, 200, 1.0 + i, 0.0, 1.0 + i, 0);
  // ids 100..104: the loaded ones of a saved map are those below 103, say, and 101 is tracked.
  const LandmarkCandidates loaded =
      landmarksWhere(s.candidates, [](std::uint64_t id) { return id < 103; });
  const LandmarkCandidates untracked = withoutLandmarks(loaded, {101});
  ASSERT_EQ(untracked.ids, (std::vector<std::uint64_t>{100, 102}));
  ASSERT_EQ(untracked.descriptors.rows, 2);
  ASSERT_EQ(untracked.points.size(), 2u);
  EXPECT_EQ(cv::norm(untracked.descriptors.row(1), s.candidates.descriptors.row(2),
                     cv::NORM_HAMMING),
            0.0);
  EXPECT_EQ(untracked.points[1], s.candidates.points[2]);
  EXPECT_TRUE(landmarksWhere(s.candidates, [](std::uint64_t) { return false; }).ids.empty());
}

}  // namespace
}  // namespace dynamap
