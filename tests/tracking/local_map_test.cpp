// LocalMap (core/src/tracking/local_map.cpp): dense ids and keyframe counts, the relocalization
// candidates of the newest keyframes, the bundle-adjustment window (which keyframes are free,
// which held fixed, which landmarks), writing a solved window back, and culled keyframes (out of
// every list, following their parent's pose).
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

TEST(LocalMap, NewestKeyframesLandmarksOnceWithoutBadOrUndescribed) {
  LocalMap map;
  buildMap(map);
  EXPECT_EQ(map.newestKeyframes(2), (std::vector<std::uint64_t>{3, 2}));
  LandmarkCandidates c = map.landmarksOf(map.newestKeyframes(2));
  // kf3 then kf2; 9 has no descriptor, 7 is listed once.
  EXPECT_EQ(c.ids, (std::vector<std::uint64_t>{7, 8, 5, 6}));
  ASSERT_EQ(c.descriptors.rows, 4);
  ASSERT_EQ(c.points.size(), 4u);
  for (int r = 0; r < 4; ++r) {
    const int id = static_cast<int>(c.ids[static_cast<std::size_t>(r)]);
    EXPECT_EQ(cv::norm(c.descriptors.row(r), descriptorOf(id), cv::NORM_HAMMING), 0.0) << id;
    EXPECT_EQ(c.points[static_cast<std::size_t>(r)], Eigen::Vector3d(id, 0, 3));
  }
  map.markBad({8, 0});
  c = map.landmarksOf(map.newestKeyframes(100));  // more keyframes than there are
  EXPECT_EQ(sorted(c.ids), (std::vector<std::uint64_t>{1, 2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(c.descriptors.rows, 7);
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

TEST(LocalMap, ARevisitsWindowHoldsTheOldKeyframesThatSawItsLandmarksFixed) {
  LocalMap map;
  buildMap(map);
  // kf4 and kf5 come back to kf0's view: kf5 sees 0 1 2 again, kf4 sees 8.
  map.addKeyframe(2.0, poseOf(0), {{8, Eigen::Vector2d(80, 5), 3.0}});
  map.addKeyframe(2.5, poseOf(0),
                  {{0, Eigen::Vector2d(0, 5), 3.0},
                   {1, Eigen::Vector2d(10, 5), 3.0},
                   {2, Eigen::Vector2d(20, 5), 3.0}});
  // Without older observers the window (kf5 free, kf4 before it) holds kf5 alone: nothing
  // ties landmarks 0 1 2 to the keyframes that made them.
  BaWindow w = map.snapshotWindow(1, 0);
  EXPECT_EQ(w.keyframe_ids, (std::vector<std::uint64_t>{5}));
  EXPECT_EQ(w.observations.size(), 3u);
  // Two older observers: kf0 (shares 0 1 2) and kf1 (shares 2), fixed, with their observations.
  w = map.snapshotWindow(1, 0, 2);
  EXPECT_EQ(w.keyframe_ids, (std::vector<std::uint64_t>{0, 1, 5}));
  EXPECT_EQ(w.fixed, (std::vector<std::uint8_t>{1, 1, 0}));
  EXPECT_EQ(w.observations.size(), 7u);  // kf0: 0 1 2; kf1: 2; kf5: 0 1 2
  EXPECT_EQ(sorted(w.landmark_ids), (std::vector<std::uint64_t>{0, 1, 2}));
  // One: the one sharing the most.
  w = map.snapshotWindow(1, 0, 1);
  EXPECT_EQ(w.keyframe_ids, (std::vector<std::uint64_t>{0, 5}));
  EXPECT_EQ(w.fixed, (std::vector<std::uint8_t>{1, 0}));
  // Only those made 2.2 s or more before the newest (kf5 at 2.5 s): kf0 at 0 s, not kf1 at 0.5.
  w = map.snapshotWindow(1, 0, 2, 2.2);
  EXPECT_EQ(w.keyframe_ids, (std::vector<std::uint64_t>{0, 5}));
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

TEST(LocalMap, CullRefusesTheFirstKeyframeANewerParentAndCulledOnes) {
  LocalMap map;
  buildMap(map);
  EXPECT_FALSE(map.cull(0, 0));  // keyframe 0 defines the world
  EXPECT_FALSE(map.cull(1, 2));  // the parent must be older
  EXPECT_FALSE(map.cull(9, 0));  // no such keyframe
  EXPECT_TRUE(map.cull(2, 1));
  EXPECT_FALSE(map.cull(2, 0));  // already culled
  EXPECT_FALSE(map.cull(3, 2));  // a culled parent
  EXPECT_TRUE(map.isCulled(2));
  EXPECT_FALSE(map.isCulled(3));
  EXPECT_EQ(map.keyframeCount(), 4u);  // ids stay dense
}

TEST(LocalMap, CulledKeyframeLeavesNearbyRelocWindowAndSavedMap) {
  LocalMap map;
  buildMap(map);
  ASSERT_TRUE(map.cull(2, 1));
  const auto near = map.keyframesNear(poseOf(2), 1.0, 10.0);
  EXPECT_EQ(sorted(near), (std::vector<std::uint64_t>{0, 1, 3}));
  EXPECT_EQ(map.newestKeyframes(2), (std::vector<std::uint64_t>{3}));  // kf2 culled
  EXPECT_EQ(sorted(map.landmarksOf(map.newestKeyframes(2)).ids), (std::vector<std::uint64_t>{7, 8}));
  const BaWindow w = map.snapshotWindow(4, 1);
  EXPECT_EQ(std::count(w.keyframe_ids.begin(), w.keyframe_ids.end(), 2u), 0);
  // Its observations (landmarks 5 6 7) constrain its parent, through the fixed offset.
  int attached = 0;
  for (const auto& o : w.observations) {
    EXPECT_NE(w.keyframe_ids[o.keyframe], 2u);
    if (o.attached < 0) continue;
    ++attached;
    EXPECT_EQ(w.keyframe_ids[o.keyframe], 1u);
  }
  EXPECT_EQ(attached, 3);
  ASSERT_EQ(w.attached.size(), 1u);
  EXPECT_TRUE(w.attached[0].isApprox(poseOf(2).inverse() * poseOf(1), 1e-12));
  const MapContents saved = map.contents();
  ASSERT_EQ(saved.keyframes.size(), 3u);
  for (std::size_t k = 0; k < saved.keyframes.size(); ++k) {
    EXPECT_EQ(saved.keyframes[k].id, k);  // renumbered densely
  }
  EXPECT_DOUBLE_EQ(saved.keyframes[2].timestamp_s, 1.5);  // kf3
  const auto kfs = map.keyframes();
  ASSERT_EQ(kfs.size(), 4u);  // every keyframe, culled ones flagged
  EXPECT_TRUE(kfs[2].culled);
  EXPECT_FALSE(kfs[3].culled);
}

TEST(LocalMap, CulledKeyframeFollowsItsParentThroughBundleAdjustment) {
  LocalMap map;
  buildMap(map);
  ASSERT_TRUE(map.cull(2, 1));
  BaWindow w = map.snapshotWindow(4, 1);  // kf0 fixed; kf1, kf3 free
  Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
  moved.translation() = Eigen::Vector3d(0.0, 0.03, 0.0);
  moved.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (std::size_t k = 0; k < w.keyframe_ids.size(); ++k) {
    if (w.keyframe_ids[k] == 1) w.poses[k] = moved * w.poses[k];
  }
  const std::vector<PoseUpdate> updates = map.apply(w);
  const auto update_of = [&](std::uint64_t id) {
    return std::find_if(updates.begin(), updates.end(),
                        [id](const PoseUpdate& u) { return u.keyframe_id == id; });
  };
  ASSERT_NE(update_of(2), updates.end());  // the culled one moved with its parent
  const Eigen::Isometry3d expected = moved * poseOf(2);
  EXPECT_TRUE(update_of(2)->T_W_C.isApprox(expected, 1e-9));
  EXPECT_TRUE(map.keyframePose(2).isApprox(expected, 1e-9));
  // The relative pose to the parent is what it was when culled.
  EXPECT_TRUE((map.keyframePose(1).inverse() * map.keyframePose(2))
                  .isApprox(poseOf(1).inverse() * poseOf(2), 1e-9));
}

}  // namespace
}  // namespace dynamap
