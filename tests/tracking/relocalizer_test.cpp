// Relocalizer (core/src/tracking/relocalizer.cpp) on rendered frames with known poses: a map of
// two keyframes of a synthetic room; a frame seen from another known pose is relocalized to that
// pose, from a wrong hint (the global search) and from a near one (the guided search); a frame of
// a room with other textures is not; fewer inliers than reloc_min_inliers do only near the last
// tracked pose.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include <opencv2/imgproc.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/tracking/depth_sampling.hpp"
#include "dynamap/core/tracking/relocalizer.hpp"
#include "synthetic_scene.hpp"

namespace dynamap {
namespace {

cv::Mat grayOf(const test::RenderedFrame& f) {
  cv::Mat gray;
  cv::cvtColor(f.bgr, gray, cv::COLOR_BGR2GRAY);
  return gray;
}

/// A keyframe as the tracker makes one: the gridded ORB keypoints with depth become landmarks
/// at their back-projection with the (here exact) keyframe pose.
void addKeyframe(const test::SyntheticScene& scene, const GridOrbExtractor& orb,
                 const TrackerConfig& config, const Eigen::Isometry3d& T_W_C, double t_s,
                 LocalMap& map) {
  const test::RenderedFrame f = scene.render(T_W_C, 0.0);
  const OrbFeatures features = orb.extract(grayOf(f), cv::Mat(), {});
  std::vector<KeyframeObservation> observations;
  for (std::size_t i = 0; i < features.keypoints.size(); ++i) {
    const cv::Point2f& p = features.keypoints[i].pt;
    const double z = sampleDepth(f.depth_m, p.x, p.y, config.depth_min_m, config.depth_max_m);
    if (z <= 0.0) continue;
    const Eigen::Vector3d p_W = T_W_C * scene.camera().backProject(p.x, p.y, z);
    const std::uint64_t id = map.addLandmark(p_W, features.descriptors.row(static_cast<int>(i)));
    observations.push_back({id, Eigen::Vector2d(p.x, p.y), z});
  }
  map.addKeyframe(t_s, T_W_C, std::move(observations));
}

struct Errors {
  double translation_m, rotation_deg;
};

Errors poseError(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  const Eigen::Isometry3d d = truth.inverse() * estimate;
  return {d.translation().norm(), Eigen::AngleAxisd(d.linear()).angle() * 180.0 / M_PI};
}

class RelocalizerTest : public ::testing::Test {
 protected:
  RelocalizerTest()
      : camera_(cameraPreset("freiburg3")),
        scene_(camera_, 12),
        orb_(config_),
        optimizer_(camera_, config_),
        relocalizer_(config_, optimizer_) {
    scene_.addDefaultRoom();
    addKeyframe(scene_, orb_, config_, test::cameraPose({0.0, 0.0, 0.0}, 0.0, 0.0), 0.0, map_);
    addKeyframe(scene_, orb_, config_, test::cameraPose({0.15, 0.02, 0.10}, 4.0, -2.0), 0.5, map_);
  }

  RelocalizationResult relocalizeFrame(const test::SyntheticScene& scene,
                                       const Eigen::Isometry3d& T_W_C,
                                       const Eigen::Isometry3d& hint) const {
    const test::RenderedFrame f = scene.render(T_W_C, 0.0);
    const OrbFeatures features = orb_.extractAll(grayOf(f), cv::Mat());
    return relocalizer_.relocalize(features, f.depth_m, map_, camera_, hint);
  }

  TrackerConfig config_;
  PinholeCamera camera_;
  test::SyntheticScene scene_;
  GridOrbExtractor orb_;
  PoseOptimizer optimizer_;
  Relocalizer relocalizer_;
  LocalMap map_;
};

// Between the two keyframes, 7 cm and 3 degrees from the nearer one.
const Eigen::Isometry3d kQueryPose = test::cameraPose({0.08, -0.03, 0.06}, 2.5, 1.5);

TEST_F(RelocalizerTest, AFrameFromAKnownPoseIsRelocalizedToItFromAWrongHint) {
  // A hint 1 m and 40 degrees off projects no landmark near its keypoint: the guided search
  // finds nothing and the global descriptor search must do it.
  const Eigen::Isometry3d wrong_hint = test::cameraPose({-0.9, 0.3, 0.5}, -40.0, 10.0);
  const RelocalizationResult r = relocalizeFrame(scene_, kQueryPose, wrong_hint);
  ASSERT_TRUE(r.ok);
  const Errors e = poseError(r.T_W_C, kQueryPose);
  // Tolerance 1 cm / 0.5 degree: pixel-accurate keypoints at 2-4 m give a few millimetres.
  EXPECT_LT(e.translation_m, 0.01);
  EXPECT_LT(e.rotation_deg, 0.5);
  EXPECT_GE(r.inliers, config_.reloc_min_inliers);
  EXPECT_EQ(r.landmark_ids.size(), static_cast<std::size_t>(r.inliers));
  ASSERT_EQ(r.px.size(), r.landmark_ids.size());
  // The inliers are where their landmarks project with the true pose: 95 % within 3 px (a
  // keypoint of a coarse pyramid level may be off by a few pixels and still be an inlier).
  std::vector<Eigen::Vector3d> points;
  map_.landmarkPositions(r.landmark_ids, points);
  int far = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d uv = camera_.project(kQueryPose.inverse() * points[i]);
    if ((uv - Eigen::Vector2d(r.px[i].x, r.px[i].y)).norm() > 3.0) ++far;
  }
  EXPECT_LE(far, r.inliers / 20) << far << " of " << r.inliers;
  std::cout << "[relocalizer] wrong hint: " << r.inliers << " inliers, error "
            << e.translation_m * 1000 << " mm, " << e.rotation_deg << " deg\n";
}

TEST_F(RelocalizerTest, ANearHintRelocalizesToTheSamePose) {
  const RelocalizationResult r = relocalizeFrame(scene_, kQueryPose, map_.keyframePose(0));
  ASSERT_TRUE(r.ok);
  const Errors e = poseError(r.T_W_C, kQueryPose);
  EXPECT_LT(e.translation_m, 0.01);
  EXPECT_LT(e.rotation_deg, 0.5);
  std::cout << "[relocalizer] near hint: " << r.inliers << " inliers, error "
            << e.translation_m * 1000 << " mm, " << e.rotation_deg << " deg\n";
}

TEST_F(RelocalizerTest, AFrameOfAnotherSceneIsNotRelocalized) {
  // The same room with other textures (another seed): descriptors match nothing consistently.
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene other(camera, 99);
  other.addDefaultRoom();
  for (const auto& hint : {kQueryPose, test::cameraPose({-0.9, 0.3, 0.5}, -40.0, 10.0)}) {
    const RelocalizationResult r = relocalizeFrame(other, kQueryPose, hint);
    EXPECT_FALSE(r.ok) << "inliers " << r.inliers;
    EXPECT_TRUE(r.landmark_ids.empty());
  }
}

TEST_F(RelocalizerTest, OnARevisitTheOldKeyframesNearTheLastPoseAreSearched) {
  // Two newer keyframes of another room 3 m away: with only the newest one searched (as the
  // tracker did before), the frame from between the two old keyframes is not relocalized.
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene elsewhere(camera, 99);
  elsewhere.addDefaultRoom();
  addKeyframe(elsewhere, orb_, config_, test::cameraPose({3.0, 0.0, 0.0}, 0.0, 0.0), 1.0, map_);
  addKeyframe(elsewhere, orb_, config_, test::cameraPose({3.1, 0.0, 0.0}, 3.0, 0.0), 1.5, map_);
  TrackerConfig newest_one = config_;
  newest_one.reloc_keyframes = 1;
  const Relocalizer relocalizer(newest_one, optimizer_);
  const test::RenderedFrame f = scene_.render(kQueryPose, 0.0);
  const OrbFeatures features = orb_.extractAll(grayOf(f), cv::Mat());
  // The last pose by the first keyframe: it (and only it: 1 + 1 candidates) is searched.
  const RelocalizationResult r =
      relocalizer.relocalize(features, f.depth_m, map_, camera_, map_.keyframePose(0));
  ASSERT_TRUE(r.ok);
  EXPECT_LT(poseError(r.T_W_C, kQueryPose).translation_m, 0.01);
  // A last pose far from every old keyframe (1 m, 40 degrees): the newest only, which fail.
  const Eigen::Isometry3d far_pose = test::cameraPose({-0.9, 0.3, 0.5}, -40.0, 10.0);
  EXPECT_FALSE(relocalizer.relocalize(features, f.depth_m, map_, camera_, far_pose).ok);
}

TEST_F(RelocalizerTest, FewerInliersDoOnlyNearTheLastTrackedPose) {
  // No number of inliers is enough by itself here: only the near-the-last-pose rule accepts.
  TrackerConfig near_only = config_;
  near_only.reloc_min_inliers = 100000;
  near_only.reloc_near_last_min_inliers = 15;
  const Relocalizer relocalizer(near_only, optimizer_);
  const test::RenderedFrame f = scene_.render(kQueryPose, 0.0);
  const OrbFeatures features = orb_.extractAll(grayOf(f), cv::Mat());
  // The last tracked pose 2.4 cm and ~1 degree from the frame's: accepted, at the true pose.
  const Eigen::Isometry3d last_pose = test::cameraPose({0.06, -0.02, 0.05}, 2.0, 1.0);
  const RelocalizationResult near =
      relocalizer.relocalize(features, f.depth_m, map_, camera_, last_pose);
  ASSERT_TRUE(near.ok);
  EXPECT_LT(poseError(near.T_W_C, kQueryPose).translation_m, 0.01);
  // The same frame with the last pose 1 m away: the pose is found but not accepted.
  const Eigen::Isometry3d far_pose = test::cameraPose({-0.9, 0.3, 0.5}, -40.0, 10.0);
  EXPECT_FALSE(relocalizer.relocalize(features, f.depth_m, map_, camera_, far_pose).ok);
  near_only.reloc_near_last_min_inliers = 0;  // off
  const Relocalizer off(near_only, optimizer_);
  EXPECT_FALSE(off.relocalize(features, f.depth_m, map_, camera_, last_pose).ok);
}

TEST_F(RelocalizerTest, LandmarksMarkedBadAreNotMatched) {
  // Every landmark of the map marked bad (seen on a mover): nothing is left to match.
  const std::vector<std::uint64_t> ids =
      map_.landmarksOf(map_.newestKeyframes(config_.reloc_keyframes)).ids;
  ASSERT_GT(ids.size(), 100u);
  map_.markBad(ids);
  const RelocalizationResult r = relocalizeFrame(scene_, kQueryPose, kQueryPose);
  EXPECT_FALSE(r.ok);
}

TEST(SeenThroughShare, AWrongPoseSeesThroughTheMapAMoverInFrontHidesIt) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  // A wall 2 m in front of the camera, and landmarks on it.
  cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
  std::vector<Eigen::Vector3d> wall;
  for (int v = 40; v < camera.height - 40; v += 40)
    for (int u = 40; u < camera.width - 40; u += 40) wall.push_back(camera.backProject(u, v, 2.0));
  int checked = 0;
  const Eigen::Isometry3d at_wall = Eigen::Isometry3d::Identity();
  EXPECT_DOUBLE_EQ(seenThroughShare(wall, at_wall, depth, camera, 0.1, 8.0, &checked), 0.0);
  EXPECT_EQ(checked, static_cast<int>(wall.size()));
  // Someone 1 m away covers the left half: those landmarks are hidden, not seen through.
  depth(cv::Rect(0, 0, camera.width / 2, camera.height)).setTo(1.0f);
  EXPECT_DOUBLE_EQ(seenThroughShare(wall, at_wall, depth, camera, 0.1, 8.0, &checked), 0.0);
  // A pose 0.5 m too close to the wall puts the landmarks at 1.5 m where 2 m is measured.
  Eigen::Isometry3d too_close = Eigen::Isometry3d::Identity();
  too_close.translation().z() = 0.5;
  EXPECT_NEAR(seenThroughShare(wall, too_close, depth, camera, 0.1, 8.0, &checked), 0.5, 0.1);
  // Without depth there is nothing to compare.
  EXPECT_DOUBLE_EQ(seenThroughShare(wall, too_close, cv::Mat::zeros(depth.size(), CV_32FC1),
                                    camera, 0.1, 8.0, &checked),
                   0.0);
  EXPECT_EQ(checked, 0);
}

}  // namespace
}  // namespace dynamap
