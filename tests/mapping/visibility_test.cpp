// The visibility pass (visibility.hpp, MappingWorker::finish()) over every backend: the synthetic
// room where the floating box stands still, unmasked, for the first half of the keyframes (a
// mover the masks missed), then moves away with masks, except one keyframe whose mask is
// missing too. The 2 + 2 neighbour free-space check cannot see through the box in its first
// keyframes (all their neighbours saw it there); later keyframes can. The static box on the floor
// is never masked and never moves (a standing person): it must stay.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "dynamap/mapping/ply_io.hpp"
#include "dynamap/mapping/visibility.hpp"
#include "map_metrics.hpp"
#include "mapping_test_utils.hpp"

namespace dynamap::test::visibility_test {
namespace {

constexpr int kFrames = 12;
constexpr int kStillUntil = 6;    // frames [0, 6): the box stands at movingBox(0), no mask
constexpr int kUnmaskedLate = 7;  // a later frame whose mask is missing as well
namespace fs = std::filesystem;

Box boxAt(int k) { return SyntheticScene::movingBox(k < kStillUntil ? 0 : k); }
bool masked(int k) { return k >= kStillUntil && k != kUnmaskedLate; }

/// Map of the scene; `all_masks` gives every frame its mask (the reference).
std::vector<Eigen::Vector3f> buildMap(const std::string& backend,
                                      const StaticPointsOptions& options, bool all_masks,
                                      const std::string& name) {
  const auto registry = BackendRegistry::scan({pluginDir()});
  const SyntheticScene scene;
  TimingRecorder timings;
  MappingWorker worker(registry.create(backend, backendCase(backend).params),
                       SyntheticScene::camera(), options, 2, &timings);
  for (int k = 0; k < kFrames; ++k) {
    worker.push(syntheticKeyframe(scene.render(k, kFrames, boxAt(k)), k, all_masks || masked(k)));
  }
  worker.finish();
  const fs::path dir = freshTempDir("visibility_" + backend + "_" + name);
  worker.exportMap(dir.string());
  return readPly(scoredFile(dir.string())).vertices;
}

/// Map points on the box where it stood unmasked (within `margin`) and off the static geometry.
std::size_t ghostPoints(const std::vector<Eigen::Vector3f>& map, double margin) {
  const SyntheticScene scene;
  std::size_t n = 0;
  for (const auto& p : map) {
    const Eigen::Vector3d q = p.cast<double>();
    const bool on_box = boxAt(0).contains(q, margin) || boxAt(kUnmaskedLate).contains(q, margin);
    n += on_box && scene.staticDistance(q) > margin ? 1 : 0;
  }
  return n;
}

/// Share of the reference points with a map point within `tol`.
double coverage(const std::vector<Eigen::Vector3f>& reference,
                const std::vector<Eigen::Vector3f>& map, double tol) {
  if (reference.empty()) return 0.0;
  const PointIndex index(map);
  std::size_t covered = 0;
  const auto t = static_cast<float>(tol);
  for (const auto& r : reference) covered += index.nearestDistance(r, t) <= t ? 1 : 0;
  return static_cast<double>(covered) / reference.size();
}

std::vector<std::string> backendNames() { return BackendRegistry::scan({pluginDir()}).names(); }

class VisibilityAllBackends : public ::testing::TestWithParam<std::string> {};

TEST_P(VisibilityAllBackends, MissedMoverIsRemovedAndStaticGeometryStays) {
  const std::string backend = GetParam();
  const double voxel = backendCase(backend).voxel_m;
  StaticPointsOptions reference_options;
  reference_options.visibility.enabled = false;
  reference_options.free_space.enabled = false;
  const auto reference = buildMap(backend, reference_options, true, "reference");
  ASSERT_GT(reference.size(), 100u);
  ASSERT_EQ(ghostPoints(reference, voxel), 0u);

  const auto map = buildMap(backend, StaticPointsOptions{}, false, "default");
  EXPECT_EQ(ghostPoints(map, voxel), 0u) << backend << ": the box where it stood unmasked";
  // All the static geometry the fully masked map has, the static box included.
  EXPECT_GT(coverage(reference, map, 2.0 * voxel), 0.99) << backend;
  std::vector<Eigen::Vector3f> static_box;
  const SyntheticScene scene;
  for (const auto& p : reference) {
    if (scene.static_box.distance(p.cast<double>()) < voxel) static_box.push_back(p);
  }
  ASSERT_GT(static_box.size(), 10u);
  EXPECT_GT(coverage(static_box, map, 2.0 * voxel), 0.99) << backend << ": the standing box";
}

// Shows the test above can fail: without the visibility pass (free-space check alone) the box
// where it stood unmasked stays in every backend's map.
TEST_P(VisibilityAllBackends, WithoutTheVisibilityPassTheMoverStays) {
  const std::string backend = GetParam();
  StaticPointsOptions options;
  options.visibility.enabled = false;
  const auto map = buildMap(backend, options, false, "off");
  EXPECT_GT(ghostPoints(map, backendCase(backend).voxel_m), 0u) << backend;
}

// The final pass over all keyframes (mapping.visibility_final_pass, the offline extra; the
// backend then gets the keyframes only in finish()) removes the mover as the online window (the
// default, every keyframe judged against those within 0.7 s after it) does, and keeps the same
// static geometry. (This test used to compare deferred and live integration before both were
// replaced by the online window: issue 47.)
TEST_P(VisibilityAllBackends, TheFinalPassRemovesTheMoverAsTheOnlineWindowDoes) {
  const std::string backend = GetParam();
  const double voxel = backendCase(backend).voxel_m;
  StaticPointsOptions final_pass;
  final_pass.visibility_final_pass = true;
  const auto offline = buildMap(backend, final_pass, false, "final_pass");
  const auto online = buildMap(backend, StaticPointsOptions{}, false, "online");
  ASSERT_GT(offline.size(), 100u);
  EXPECT_EQ(ghostPoints(offline, voxel), 0u) << backend;
  EXPECT_EQ(ghostPoints(online, voxel), 0u) << backend;
  EXPECT_GT(coverage(offline, online, 2.0 * voxel), 0.99) << backend;
  EXPECT_GT(coverage(online, offline, 2.0 * voxel), 0.99) << backend;
}

INSTANTIATE_TEST_SUITE_P(AllBackends, VisibilityAllBackends, ::testing::ValuesIn(backendNames()),
                         [](const auto& info) { return info.param; });
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(VisibilityAllBackends);

// Mask votes: a box that never moves while the camera moves (so no keyframe ever sees through
// it) but that the masks mark as moving in all keyframes except two: most views say "mover", so
// the two unmasked keyframes' points of it go (but for its rim); the never-masked static box stays.
// Without the votes (mask_min_views = 0) the box stays.
TEST(Visibility, MaskVotesRemoveWhatMostKeyframesMasked) {
  const SyntheticScene scene;
  const auto build = [&](int mask_min_views) {
    StaticPointsOptions options;
    options.visibility.mask_min_views = mask_min_views;
    TimingRecorder timings;
    MappingWorker worker(BackendRegistry::scan({pluginDir()}).create("points", {}),
                         SyntheticScene::camera(), options, 2, &timings);
    for (int k = 0; k < kFrames; ++k) {
      const SyntheticFrame f = scene.render(k, kFrames, boxAt(0));
      auto kf = std::make_shared<KeyframePacket>();
      kf->id = static_cast<std::uint64_t>(k);
      kf->T_W_C = f.T_W_C;
      kf->bgr = f.bgr;
      kf->depth_m = f.depth_m;
      if (k != 3 && k != 8) kf->dynamic_mask = f.mask;
      worker.push(kf);
    }
    worker.finish();
    const fs::path dir = freshTempDir("visibility_votes_" + std::to_string(mask_min_views));
    worker.exportMap(dir.string());
    return readPly((dir / "cloud.ply").string()).vertices;
  };
  const auto on_box = [](const std::vector<Eigen::Vector3f>& map) {
    std::size_t n = 0;
    for (const auto& p : map) n += boxAt(0).contains(p.cast<double>(), 0.01) ? 1 : 0;
    return n;
  };
  const auto voted = build(2);
  const std::size_t without = on_box(build(0));
  EXPECT_GT(without, 1000u);
  // Its rim (blocks of the view less than half under the mask) may stay: at most 5 %.
  EXPECT_LT(on_box(voted), 0.05 * without);
  std::size_t standing = 0;
  for (const auto& p : voted) standing += scene.static_box.distance(p.cast<double>()) < 0.01;
  EXPECT_GT(standing, 500u);
}

// A view's mask blocks (1/4 resolution: at least half the block masked) take the mask grown by
// mask_grow_px: a mask whose edge lies 1 px into a block column (its margin taken off the
// background) marks the column when grown by 3, and not when taken as it is.
TEST(Visibility, ViewMasksGrowByMaskGrowPx) {
  const cv::Mat depth(480, 640, CV_32FC1, cv::Scalar(2.f));
  cv::Mat mask = cv::Mat::zeros(depth.size(), CV_8UC1);
  mask(cv::Rect(0, 0, 317, 480)).setTo(255);  // block column 79 (x 316-319): 1 px masked
  VisibilityOptions options;
  options.mask_grow_px = 0;
  const VisibilityView plain = makeVisibilityView(depth, mask, options);
  options.mask_grow_px = 3;
  const VisibilityView grown = makeVisibilityView(depth, mask, options);
  ASSERT_EQ(plain.downsample, 4);
  EXPECT_EQ(plain.moving.at<uchar>(60, 78), 255);
  EXPECT_EQ(plain.moving.at<uchar>(60, 79), 0);
  EXPECT_EQ(grown.moving.at<uchar>(60, 79), 255);  // grown to x 319
  EXPECT_EQ(grown.moving.at<uchar>(60, 80), 0);
  EXPECT_EQ(cv::countNonZero(grown.moving) - cv::countNonZero(plain.moving), 120);
}

// removeSeenThrough() alone: a keyframe that saw through a surface removes it, one that saw it
// (or saw something nearer along the ray) does not; the depth image is edited in place.
TEST(Visibility, RemovesOnlyWhatAnotherKeyframeSawThrough) {
  const PinholeCamera cam = SyntheticScene::camera();
  const SyntheticScene scene;
  const SyntheticFrame with_box = scene.render(0, 4, boxAt(0));
  const SyntheticFrame without_box = scene.render(3, 4, Box{{9, 9, 9}, {9.1, 9.1, 9.1}});
  const SyntheticFrame again = scene.render(1, 4, boxAt(0));
  cv::Mat d0 = with_box.depth_m.clone(), d1 = again.depth_m.clone();
  const int box_px = cv::countNonZero(with_box.mask);
  ASSERT_GT(box_px, 200);
  VisibilityOptions options;
  const VisibilityView v0 = makeVisibilityView(with_box.depth_m, cv::Mat(), options);
  const VisibilityView v1 = makeVisibilityView(again.depth_m, cv::Mat(), options);
  const VisibilityView v2 = makeVisibilityView(without_box.depth_m, cv::Mat(), options);
  std::vector<VisibilityKeyframe> kfs = {{&d0, 1.0, with_box.T_W_C, &v0},
                                         {&d1, 1.0, again.T_W_C, &v1}};
  // Two keyframes that both saw the box: nothing removed.
  EXPECT_EQ(removeSeenThrough(cam, kfs, options).removed_pixels, 0u);
  EXPECT_EQ(cv::countNonZero(d0 != with_box.depth_m), 0);
  // A third one that saw through where the box was: the box goes, in both, and only the box.
  cv::Mat d2 = without_box.depth_m.clone();
  kfs.push_back({&d2, 1.0, without_box.T_W_C, &v2});
  const VisibilityResult r = removeSeenThrough(cam, kfs, options);
  EXPECT_GT(r.seen_through, 0u);
  const cv::Mat removed0 = (d0 == 0) & (with_box.depth_m > 0);
  EXPECT_GT(cv::countNonZero(removed0 & with_box.mask), 0.9 * box_px);
  EXPECT_LT(cv::countNonZero(removed0 & ~with_box.mask), 0.02 * box_px);
  EXPECT_EQ(cv::countNonZero(d2 != without_box.depth_m), 0);
  EXPECT_EQ(r.per_keyframe_ms.size(), 3u);
}

/// n keyframes of the room: the floating box where it first stood, unmasked, in the first two,
/// far away in the others. pass() runs copies of their depth through the visibility pass, after
/// `edit` had its say on the depths and the keyframes.
struct BoxInFirstTwo {
  explicit BoxInFirstTwo(int n) {
    const SyntheticScene scene;
    for (int k = 0; k < n; ++k)
      frames.push_back(scene.render(k, n, k < 2 ? boxAt(0) : Box{{9, 9, 9}, {9.1, 9.1, 9.1}}));
    for (const auto& f : frames) views.push_back(makeVisibilityView(f.depth_m, cv::Mat(), options));
  }
  template <typename Edit>
  VisibilityResult pass(std::vector<cv::Mat>& depths, const Edit& edit) const {
    depths.clear();
    for (const auto& f : frames) depths.push_back(f.depth_m.clone());
    std::vector<VisibilityKeyframe> kfs;
    for (std::size_t k = 0; k < frames.size(); ++k)
      kfs.push_back({&depths[k], 1.0, frames[k].T_W_C, &views[k]});
    edit(depths, kfs);
    return removeSeenThrough(SyntheticScene::camera(), kfs, options);
  }
  VisibilityOptions options;
  std::vector<SyntheticFrame> frames;
  std::vector<VisibilityView> views;
};

// The pass splits its work over two threads: an odd number of keyframes (the last pair has one)
// gives the same edits and counts on every call, and a box left unmasked in the first keyframes
// is removed from each of them.
TEST(Visibility, TwoThreadsGiveTheSameResultEveryTime) {
  constexpr int kKeyframes = 5;
  const BoxInFirstTwo scene(kKeyframes);
  const auto as_is = [](auto&, auto&) {};
  std::vector<cv::Mat> first, second;
  const VisibilityResult a = scene.pass(first, as_is), b = scene.pass(second, as_is);
  EXPECT_EQ(a.elements, b.elements);
  EXPECT_EQ(a.seen_through, b.seen_through);
  EXPECT_EQ(a.removed_pixels, b.removed_pixels);
  ASSERT_EQ(a.per_keyframe_ms.size(), static_cast<std::size_t>(kKeyframes));
  for (int k = 0; k < kKeyframes; ++k) EXPECT_EQ(cv::countNonZero(first[k] != second[k]), 0) << k;
  for (int k = 0; k < 2; ++k) {
    const SyntheticFrame& f = scene.frames[k];
    const int box_px = cv::countNonZero(f.mask);
    ASSERT_GT(box_px, 200);
    const cv::Mat removed = (first[k] == 0) & (f.depth_m > 0);
    EXPECT_GT(cv::countNonZero(removed & f.mask), 0.9 * box_px) << k;
    EXPECT_LT(cv::countNonZero(removed & ~f.mask), 0.02 * box_px) << k;
  }
}

constexpr int kWithout = 5;  // AKeyframeWithoutStaticDepthOnlyVotes: the keyframe without depth

// A keyframe without static depth (nullptr) gives no points but still votes with its view: the
// same edits and counts as a keyframe whose static depth is all zero. 9 keyframes: the pass keys
// them four at a time, so the batches are 4, 4 and 1.
TEST(Visibility, AKeyframeWithoutStaticDepthOnlyVotes) {
  constexpr int kKeyframes = 9;
  const BoxInFirstTwo scene(kKeyframes);
  std::vector<cv::Mat> with_null, with_zeros;
  const VisibilityResult a = scene.pass(with_null, [](auto& depths, auto& kfs) {
    depths[kWithout].setTo(0.0f);
    kfs[kWithout].static_depth = nullptr;
  });
  const VisibilityResult b =
      scene.pass(with_zeros, [](auto& depths, auto&) { depths[kWithout].setTo(0.0f); });
  EXPECT_EQ(a.elements, b.elements);
  EXPECT_EQ(a.seen_through, b.seen_through);
  EXPECT_EQ(a.mask_voted, b.mask_voted);
  EXPECT_EQ(a.removed_pixels, b.removed_pixels);
  EXPECT_GT(a.removed_pixels, 200u);  // the box of the first two keyframes
  for (int k = 0; k < kKeyframes; ++k) {
    EXPECT_EQ(cv::countNonZero(with_null[k] != with_zeros[k]), 0) << k;
  }
}

}  // namespace
}  // namespace dynamap::test::visibility_test
