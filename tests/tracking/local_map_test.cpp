// LocalMap (core/src/tracking/local_map.cpp): dense ids and keyframe counts, the relocalization
// candidates of the newest keyframes, the bundle-adjustment window (which keyframes are free,
// which held fixed, which landmarks) and writing a solved window back.
#include <gtest/gtest.h>

#include <algorithm>

#include "dynamap/core/tracking/local_map.hpp"

namespace dynamap {
namespace {

cv::Mat descriptorOf(int i) { return cv::Mat(1, 32, CV_8U, cv::Scalar(i + 1)); }

Eigen::Isometry3d poseOf(int k) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.1 * k, 0.0, 0.0);
  return T;
}

/// Ten landmarks (9 without a descriptor) and four keyframes:
/// kf0 sees 0 1 2 3, kf1 sees 2 3 4 5, kf2 sees 5 6 7, kf3 sees 7 8 9.
void buildMap(LocalMap& map) {
  for (int i = 0; i < 10; ++i) {
    const std::uint64_t id =
        map.addLandmark(Eigen::Vector3d(i, 0.0, 3.0), i == 9 ? cv::Mat() : descriptorOf(i));
    ASSERT_EQ(id, static_cast<std::uint64_t>(i));
  }
  const std::vector<std::vector<std::uint64_t>> seen = {
      {0, 1, 2, 3}, {2, 3, 4, 5}, {5, 6, 7}, {7, 8, 9}};
  for (int k = 0; k < 4; ++k) {
    std::vector<KeyframeObservation> obs;
    for (const auto id : seen[static_cast<std::size_t>(k)]) {
      obs.push_back({id, Eigen::Vector2d(10.0 * static_cast<double>(id), 5.0), 3.0});
    }
    ASSERT_EQ(map.addKeyframe(0.5 * k, poseOf(k), std::move(obs)), static_cast<std::uint64_t>(k));
  }
}

std::vector<std::uint64_t> sorted(std::vector<std::uint64_t> v) {
  std::sort(v.begin(), v.end());
  return v;
}

TEST(LocalMap, IdsAreDenseAndKeyframeCountsFollowObservations) {
  LocalMap map;
  buildMap(map);
  EXPECT_EQ(map.keyframeCount(), 4u);
  EXPECT_TRUE(map.keyframePose(2).isApprox(poseOf(2)));
  std::vector<int> counts;
  map.keyframeCounts({0, 2, 5, 7, 9}, counts);
  EXPECT_EQ(counts, (std::vector<int>{1, 2, 2, 2, 1}));
  std::vector<Eigen::Vector3d> points;
  map.landmarkPositions({4, 8}, points);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[0], Eigen::Vector3d(4, 0, 3));
  EXPECT_EQ(points[1], Eigen::Vector3d(8, 0, 3));
  const auto kfs = map.keyframes();
  ASSERT_EQ(kfs.size(), 4u);
  EXPECT_DOUBLE_EQ(kfs[3].timestamp_s, 1.5);
  EXPECT_FALSE(map.isBad(3));
  map.markBad({3, 1000});  // an unknown id is ignored
  EXPECT_TRUE(map.isBad(3));
  EXPECT_FALSE(map.isBad(1000));
}

TEST(LocalMap, RelocCandidatesAreTheNewestKeyframesLandmarksOnceWithoutBadOrUndescribed) {
  LocalMap map;
  buildMap(map);
  std::vector<std::uint64_t> ids;
  cv::Mat descriptors;
  std::vector<Eigen::Vector3d> points;
  map.relocCandidates(2, ids, descriptors, points);
  // kf3 then kf2; 9 has no descriptor, 7 is listed once.
  EXPECT_EQ(ids, (std::vector<std::uint64_t>{7, 8, 5, 6}));
  ASSERT_EQ(descriptors.rows, 4);
  ASSERT_EQ(points.size(), 4u);
  for (int r = 0; r < 4; ++r) {
    const int id = static_cast<int>(ids[static_cast<std::size_t>(r)]);
    EXPECT_EQ(cv::norm(descriptors.row(r), descriptorOf(id), cv::NORM_HAMMING), 0.0) << id;
    EXPECT_EQ(points[static_cast<std::size_t>(r)], Eigen::Vector3d(id, 0, 3));
  }
  map.markBad({8, 0});
  map.relocCandidates(100, ids, descriptors, points);  // more keyframes than there are
  EXPECT_EQ(sorted(ids), (std::vector<std::uint64_t>{1, 2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(descriptors.rows, 7);
}

TEST(LocalMap, WindowHoldsOlderCovisibleKeyframesFixedAndLeavesBadLandmarksOut) {
  LocalMap map;
  buildMap(map);
  // Newest 2 keyframes, the oldest of them fixed: kf3 free; its landmarks 7 8 9; kf2 sees 7 and
  // joins fixed; kf0 and kf1 see none of them and stay out.
  BaWindow w = map.snapshotWindow(2, 1);
  EXPECT_EQ(w.keyframe_ids, (std::vector<std::uint64_t>{2, 3}));
  EXPECT_EQ(w.fixed, (std::vector<std::uint8_t>{1, 0}));
  EXPECT_EQ(sorted(w.landmark_ids), (std::vector<std::uint64_t>{7, 8, 9}));
  EXPECT_EQ(w.observations.size(), 4u);  // kf2: 7; kf3: 7 8 9
  for (const auto& o : w.observations) {
    const auto id = w.landmark_ids[static_cast<std::size_t>(o.landmark)];
    EXPECT_DOUBLE_EQ(o.px.x(), 10.0 * static_cast<double>(id));
    EXPECT_TRUE(w.poses[static_cast<std::size_t>(o.keyframe)].isApprox(
        poseOf(static_cast<int>(w.keyframe_ids[static_cast<std::size_t>(o.keyframe)]))));
  }

  // Keyframe 0 defines the world: fixed even with no fixed keyframes asked for.
  w = map.snapshotWindow(10, 0);
  EXPECT_EQ(w.keyframe_ids, (std::vector<std::uint64_t>{0, 1, 2, 3}));
  EXPECT_EQ(w.fixed, (std::vector<std::uint8_t>{1, 0, 0, 0}));

  // A bad landmark leaves the window with its observations; kf2 then shares nothing with kf3.
  map.markBad({7});
  w = map.snapshotWindow(1, 0);
  EXPECT_EQ(w.keyframe_ids, (std::vector<std::uint64_t>{3}));
  EXPECT_EQ(sorted(w.landmark_ids), (std::vector<std::uint64_t>{8, 9}));
  EXPECT_EQ(w.observations.size(), 2u);

  LocalMap single;
  single.addLandmark(Eigen::Vector3d(0, 0, 2), descriptorOf(0));
  single.addKeyframe(0.0, Eigen::Isometry3d::Identity(), {{0, Eigen::Vector2d(1, 1), 2.0}});
  EXPECT_TRUE(single.snapshotWindow(8, 1).keyframe_ids.empty());  // nothing free to solve
}

TEST(LocalMap, ApplyWritesFreePosesAndPointsAndReportsOnlyMovedKeyframes) {
  LocalMap map;
  buildMap(map);
  BaWindow w = map.snapshotWindow(2, 1);  // kf2 fixed, kf3 free
  Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
  moved.translation() = Eigen::Vector3d(0.0, 0.02, 0.0);
  for (auto& T : w.poses) T = T * moved;  // the fixed one too: apply must not write it
  for (auto& p : w.points) p += Eigen::Vector3d(0.0, 0.0, 0.5);
  const std::vector<PoseUpdate> updates = map.apply(w);
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_EQ(updates[0].keyframe_id, 3u);
  EXPECT_TRUE(updates[0].T_W_C.isApprox(poseOf(3) * moved));
  EXPECT_TRUE(map.keyframePose(3).isApprox(poseOf(3) * moved));
  EXPECT_TRUE(map.keyframePose(2).isApprox(poseOf(2)));
  std::vector<Eigen::Vector3d> points;
  map.landmarkPositions({7, 8, 9, 6}, points);
  EXPECT_EQ(points[0], Eigen::Vector3d(7, 0, 3.5));
  EXPECT_EQ(points[1], Eigen::Vector3d(8, 0, 3.5));
  EXPECT_EQ(points[2], Eigen::Vector3d(9, 0, 3.5));
  EXPECT_EQ(points[3], Eigen::Vector3d(6, 0, 3));  // not in the window
}

}  // namespace
}  // namespace dynamap
