// LoopCloser (core/src/tracking/loop_closer.cpp) end to end on rendered keyframes:
// - a room the camera circles 1.25 times (60 keyframes, 7.5 deg apart) with odometry drifting
//   (0.3 deg of yaw and 0.1 deg of pitch per keyframe, seeded noise): the revisit is detected,
//   every accepted loop agrees with the truth, and the pose graph removes >= 80 % of the
//   end-point error;
// - a corridor walked once, with a poster repeated at two places of one wall and a box moving
//   along with the camera (masked): no loop is accepted; with the mask ignored and verification
//   relaxed, the same keyframes do produce false loops (the scene is a real trap).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "loop_test_scene.hpp"

namespace dynamap {
namespace {

TrackerConfig testConfig() { return TrackerConfig{}; }

// Tolerances: end-point error after <= 20 % of before (the issue's >= 80 % reduction); every
// accepted loop's relative pose within 5 cm and 2 deg of the truth; at least one loop found.
TEST(LoopClosure, RevisitRemovesInjectedDrift) {
  const TrackerConfig config = testConfig();
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 21);
  test::addLoopRoom(scene);
  GridOrbExtractor orb(config);
  TimingRecorder timings;
  LoopCloser closer(camera, config, LoopCloserConfig{}, &timings);
  std::mt19937 rng(3);

  // As the tracker would: each keyframe added with the generation of the corrections it has
  // applied; a detected loop is closed at once and the correction applied to the estimate.
  constexpr int kKeyframes = 60;
  std::vector<Eigen::Isometry3d> truth, estimate, odometry_only;
  int generation = 0, closes = 0;
  for (int k = 0; k < kKeyframes; ++k) {
    truth.push_back(test::circleKeyframePose(k));
    if (k == 0) {
      estimate.push_back(truth[0]);
      odometry_only.push_back(truth[0]);
    } else {
      const Eigen::Isometry3d step = test::driftingStep(truth[k - 1], truth[k], rng);
      estimate.push_back(estimate.back() * step);
      odometry_only.push_back(odometry_only.back() * step);
    }
    const test::RenderedFrame f = scene.render(truth[k], 0.0);
    LoopKeyframeInput kf = test::makeLoopKeyframe(static_cast<std::uint64_t>(k), f, estimate[k],
                                                  orb, config, true, rng);
    kf.generation = generation;
    closer.addKeyframe(std::move(kf));
    if (!closer.detect()) continue;
    const auto correction = closer.close();
    ASSERT_TRUE(correction.has_value());
    ASSERT_EQ(correction->keyframes.size(), static_cast<std::size_t>(k + 1));
    for (const PoseCorrection& c : correction->keyframes) estimate[c.id] = c.T_W_C_after;
    generation = correction->generation;
    ++closes;
  }
  ASSERT_FALSE(closer.loops().empty()) << "no loop detected";
  for (const LoopConstraint& l : closer.loops()) {
    const Eigen::Isometry3d T_true = truth[l.match_id].inverse() * truth[l.query_id];
    const double dt = (l.T_Cmatch_Cquery.translation() - T_true.translation()).norm();
    const double dr = test::rotationDeg(l.T_Cmatch_Cquery, T_true);
    std::cout << "loop " << l.query_id << " -> " << l.match_id << ": " << l.inliers
              << " inliers, hull " << l.hull_share << ", neighbours " << l.consistent_neighbours
              << ", error " << dt << " m " << dr << " deg\n";
    EXPECT_LT(dt, 0.05);
    EXPECT_LT(dr, 2.0);
  }
  const double before = (odometry_only.back().translation() - truth.back().translation()).norm();
  const double after = (estimate.back().translation() - truth.back().translation()).norm();
  std::cout << "end-point error " << before << " m -> " << after << " m ("
            << 100.0 * (1.0 - after / before) << " % less), rotation "
            << test::rotationDeg(odometry_only.back(), truth.back()) << " -> "
            << test::rotationDeg(estimate.back(), truth.back()) << " deg; "
            << closer.loops().size() << " loops, " << closes << " closes\n";
  const StageStats detect = timings.stats("loop_detect"), close = timings.stats("loop_close");
  std::cout << "loop_detect per keyframe: median " << detect.median_ms << " ms, max "
            << detect.max_ms << " ms; loop_close " << close.median_ms << " ms\n";
  EXPECT_GT(before, 0.2);
  EXPECT_LE(after, 0.2 * before);
}

/// A corridor (walls 1.6 m either side, panels of 2 m) walked once along +z, looking at the left
/// wall; a poster (1.0 x 0.75 m, the same texture: scenes of the same seed) hangs on that wall
/// at z = 2 m and, 0.35 m lower, at z = 8.5 m; a box 0.75 m in front of the camera moves with it.
struct Corridor {
  explicit Corridor(const PinholeCamera& camera)
      : walls(camera, 31), poster_a(camera, 99), poster_b(camera, 99) {
    for (int i = 0; i < 8; ++i) {
      const double z = -2.0 + 2.0 * i;
      walls.addPlane({-1.6, -1.5, z}, {0, 0, 2.0}, {0, 2.8, 0});  // left wall
      walls.addPlane({-1.6, 1.3, z}, {3.2, 0, 0}, {0, 0, 2.0});   // floor
      walls.addPlane({-1.6, -1.5, z}, {3.2, 0, 0}, {0, 0, 2.0});  // ceiling
    }
    walls.addMovingBox({-0.8, 0.1, 0.0}, {0.05, 0.2, 0.25}, {0.0, 0.0, kSpeed_mps});
    poster_a.addPlane({-1.58, -0.45, 2.0}, {0, 0, 1.0}, {0, 0.75, 0});
    poster_b.addPlane({-1.58, -0.10, 8.5}, {0, 0, 1.0}, {0, 0.75, 0});
  }
  static Eigen::Isometry3d pose(int k) { return test::cameraPose({0.0, 0.0, kStep_m * k}, -90, 0); }
  static double time(int k) { return kStep_m * k / kSpeed_mps; }
  test::RenderedFrame render(int k) const {
    return test::renderComposite({&walls, &poster_a, &poster_b}, pose(k), time(k));
  }
  static constexpr double kStep_m = 0.25, kSpeed_mps = 1.0;
  test::SyntheticScene walls, poster_a, poster_b;
};

/// Every loop `closer` accepts over the corridor's keyframes (all false: no place is revisited).
std::vector<LoopConstraint> corridorLoops(const std::vector<test::RenderedFrame>& frames,
                                          const LoopCloserConfig& loop_config, bool use_mask) {
  const TrackerConfig config = testConfig();
  const PinholeCamera camera = cameraPreset("freiburg3");
  GridOrbExtractor orb(config);
  LoopCloser closer(camera, config, loop_config, nullptr);
  std::mt19937 rng(4);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const int i = static_cast<int>(k);
    closer.addKeyframe(
        test::makeLoopKeyframe(k, frames[k], Corridor::pose(i), orb, config, use_mask, rng));
    closer.detect();
  }
  for (const LoopConstraint& l : closer.loops()) {
    std::cout << "  false loop " << l.query_id << " -> " << l.match_id << ": " << l.inliers
              << " inliers, hull " << l.hull_share << ", neighbours " << l.consistent_neighbours
              << ", moved " << l.T_Cmatch_Cquery.translation().norm() << " m\n";
  }
  return closer.loops();
}

// Tolerance: no accepted loop at all with the defaults, with the movers' mask (the contract:
// static features only) and without it (the candidate's neighbours disagree with a loop seen on
// a box that travels with the camera). The scene must be a trap for this to mean something, so
// two controls with verification reduced to inlier counts accept false loops: the mover's with
// the mask ignored (15 inliers), the poster's with the mask (8 inliers, every voted candidate).
TEST(LoopClosure, RepeatedPosterAndMoverGiveNoFalseLoop) {
  const Corridor corridor(cameraPreset("freiburg3"));
  std::vector<test::RenderedFrame> frames;
  for (int k = 0; k < 48; ++k) frames.push_back(corridor.render(k));

  std::cout << "defaults, movers masked:\n";
  EXPECT_TRUE(corridorLoops(frames, LoopCloserConfig{}, true).empty());
  std::cout << "defaults, movers not masked:\n";
  EXPECT_TRUE(corridorLoops(frames, LoopCloserConfig{}, false).empty());

  LoopCloserConfig counts_only;
  counts_only.verify.min_hull_share = 0.0;
  counts_only.verify.min_consistent_neighbours = 0;
  counts_only.verify.min_inliers = 15;
  std::cout << "control: inlier count only, movers not masked:\n";
  EXPECT_FALSE(corridorLoops(frames, counts_only, false).empty());
  counts_only.verify.min_inliers = 8;
  counts_only.min_vote_share = 0.0;
  counts_only.max_candidates = 20;
  std::cout << "control: inlier count only, movers masked (the poster):\n";
  const auto poster_loops = corridorLoops(frames, counts_only, true);
  EXPECT_FALSE(poster_loops.empty());
}

}  // namespace
}  // namespace dynamap
