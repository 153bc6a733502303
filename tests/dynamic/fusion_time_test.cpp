// Fusion decisions that take time: keeping a person needs quiet frames (and a still world
// position), removing one needs a single frame; confirmed-static objects are not swallowed by
// a mover's depth cut; missed detections keep their mask; only proven-static points carve.
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "dynamap/core/dynamic/class_table.hpp"
#include "dynamap/core/dynamic/region_fusion.hpp"
#include "mask_share.hpp"

namespace dynamap::fusion_time_test {
namespace {

constexpr int kPerson = 0;

struct Scene {
  cv::Mat depth = cv::Mat(480, 640, CV_32F, cv::Scalar(4.f));
  std::vector<cv::Point2f> points;
  std::vector<std::uint8_t> quiet;  ///< no point flagged

  Scene() {
    for (int y = 5; y < 480; y += 10)
      for (int x = 5; x < 640; x += 10) points.emplace_back(float(x), float(y));
    quiet.assign(points.size(), 0);
  }
  void place(const cv::Rect& r, float z) { depth(r).setTo(z); }
  std::vector<std::uint8_t> flagged(const cv::Rect& r) const {
    std::vector<std::uint8_t> f(points.size(), 0);
    for (std::size_t i = 0; i < points.size(); ++i) f[i] = r.contains(cv::Point(points[i]));
    return f;
  }
};

Detection box(const cv::Rect& r) {
  return {cv::Rect2f(r.x - 10, r.y - 10, r.width + 20, r.height + 20), kPerson, 0.9f};
}

using test::maskedShare;

TEST(FusionOverTime, KeepingAPersonTakesQuietFramesRemovingOneTakesOne) {
  Scene s;
  const cv::Rect person(200, 150, 80, 250);
  s.place(person, 2.f);
  DynamicConfig c;
  c.static_confirm_frames = 5;
  RegionFusion fusion(c, ClassTable(c));
  for (int i = 0; i + 1 < c.static_confirm_frames; ++i) {  // quiet, but not yet long enough
    const FusionResult r =
        fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.quiet, {box(person)});
    EXPECT_TRUE(r.objects.at(0).moving) << "frame " << i;
    EXPECT_GT(maskedShare(r.mask, person), 0.99);
  }
  FusionResult r = fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.quiet, {box(person)});
  EXPECT_FALSE(r.objects.at(0).moving);
  EXPECT_LT(maskedShare(r.mask, person), 0.01);
  // One frame of clear motion masks it again, and the count starts over.
  r = fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.flagged(person), {box(person)});
  EXPECT_TRUE(r.objects.at(0).moving);
  r = fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.quiet, {box(person)});
  EXPECT_TRUE(r.objects.at(0).moving);
}

TEST(FusionOverTime, QuietFramesMeasuredAmongMoversAreNoEvidence) {
  Scene s;
  const cv::Rect person(200, 150, 80, 250);
  s.place(person, 2.f);
  DynamicConfig c;
  RegionFusion fusion(c, ClassTable(c));
  FusionEvidence ev;
  ev.background_fit = false;  // the camera motion was fitted on the people themselves
  FusionResult r;
  for (int i = 0; i < 3 * c.static_confirm_frames; ++i)
    r = fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.quiet, {box(person)}, ev);
  EXPECT_TRUE(r.objects.at(0).moving);
}

TEST(FusionOverTime, ASlowWalkerWhosePointsPassEveryFrameIsNeverKept) {
  // 3 cm per frame sideways at 2 m: 8 px, flagged by no frame-to-frame check here (all quiet),
  // but its world position drifts beyond static_max_drift_m.
  DynamicConfig c;
  c.static_max_drift_m = 0.1;
  RegionFusion fusion(c, ClassTable(c));
  FusionEvidence ev;
  ev.has_pose = true;
  ev.K = cv::Vec4d(535.4, 539.2, 320.1, 247.6);
  int kept = 0;
  for (int i = 0; i < 30; ++i) {
    Scene s;
    const cv::Rect walker(100 + 8 * i, 150, 80, 250);
    s.place(walker, 2.f);
    kept += !fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.quiet, {box(walker)}, ev)
                 .objects.at(0)
                 .moving;
  }
  // Confirmation needs static_confirm_frames (5) frames within 0.1 m of where the run began:
  // at 3 cm a frame a run lasts 4 frames, so it is never reached.
  EXPECT_EQ(kept, 0);
  // The same person standing still is kept.
  RegionFusion still(c, ClassTable(c));
  Scene s;
  const cv::Rect standing(150, 150, 80, 250);
  s.place(standing, 2.f);
  FusionResult r;
  for (int i = 0; i < 2 * c.static_confirm_frames; ++i)
    r = still.fuse(FusionMode::kBoth, s.depth, s.points, s.quiet, {box(standing)}, ev);
  EXPECT_FALSE(r.objects.at(0).moving);
}

TEST(FusionOverTime, AConfirmedStaticObjectIsNotSwallowedByAMoversBox) {
  // A teddy (confirmed static) at 2 m; a walker at 2.1 m beside it whose box covers the teddy
  // too: the walker's depth cut takes both, the teddy's pixels must stay unmasked.
  Scene s;
  const cv::Rect teddy(300, 200, 120, 150), walker(440, 120, 70, 300);
  s.place(teddy, 2.f);
  s.place(walker, 2.1f);
  DynamicConfig c;
  RegionFusion fusion(c, ClassTable(c));
  const Detection teddy_box = box(teddy);
  for (int i = 0; i <= c.static_confirm_frames; ++i)
    fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.quiet, {teddy_box});
  const Detection wide{cv::Rect2f(290, 110, 230, 320), kPerson, 0.8f};
  const FusionResult r =
      fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.flagged(walker), {teddy_box, wide});
  EXPECT_GT(maskedShare(r.mask, walker), 0.9);
  EXPECT_LT(maskedShare(r.mask, teddy), 0.05);
}

TEST(FusionOverTime, AMissedDetectionKeepsItsMaskCarriedByTheFlow) {
  Scene s0;
  const cv::Rect walker(200, 150, 80, 250);
  s0.place(walker, 2.f);
  DynamicConfig c;
  RegionFusion fusion(c, ClassTable(c));
  fusion.fuse(FusionMode::kBoth, s0.depth, s0.points, s0.flagged(walker), {box(walker)});
  // Next frame: the walker moved 12 px right, the detector saw nothing.
  Scene s1;
  const cv::Rect moved = walker + cv::Point(12, 0);
  s1.place(moved, 2.f);
  FusionEvidence ev;
  ev.prev_points = s1.points;
  for (std::size_t i = 0; i < s1.points.size(); ++i) {
    if (moved.contains(cv::Point(s1.points[i]))) ev.prev_points[i].x -= 12.f;
  }
  const FusionResult r =
      fusion.fuse(FusionMode::kBoth, s1.depth, s1.points, s1.flagged(moved), {}, ev);
  ASSERT_EQ(r.objects.size(), 1u);
  EXPECT_TRUE(r.objects[0].carried);
  EXPECT_GT(maskedShare(r.mask, moved), 0.95);
  // Without the track (a fresh fusion), nothing but the geometric clusters would mask it.
  EXPECT_EQ(r.clusters, 0);
}

/// The share of `walker` masked in `next`, the frame after one where he was detected at 2 m
/// (with carried_border_exit = `check`): no detection and no flow in `next`, his points
/// flagged there if `flagged`.
double carriedMaskShare(const cv::Rect& walker, bool check, const Scene& next, bool flagged) {
  Scene s0;
  s0.place(walker, 2.f);
  DynamicConfig c;
  c.carried_border_exit = check;
  RegionFusion fusion(c, ClassTable(c));
  fusion.fuse(FusionMode::kBoth, s0.depth, s0.points, s0.flagged(walker), {box(walker)});
  FusionEvidence ev;
  ev.prev_points = next.points;  // no flow
  const FusionResult r = fusion.fuse(FusionMode::kBoth, next.depth, next.points,
                                     flagged ? next.flagged(walker) : next.quiet, {}, ev);
  EXPECT_EQ(r.objects.size(), 1u);
  EXPECT_TRUE(!r.objects.empty() && r.objects[0].carried);
  return maskedShare(r.mask, walker);
}

// A walker at the left image border walks out of the image; the detector reports nothing more.
// The carried box's centre now shows only the wall: it masks nothing there (without the check it
// took the wall, 12-15 k pixels a frame on teddy_dyn_crowd_dev). A walker still there at his own
// depth, the detector missing him, keeps his mask.
TEST(FusionOverTime, ACarriedBoxAtTheBorderMasksNoWallOnceItsWalkerLeft) {
  const cv::Rect walker(0, 150, 70, 250);
  const auto carried = [&](bool check, bool still_there) {
    Scene s1;
    if (still_there) s1.place(walker, 2.f);
    return carriedMaskShare(walker, check, s1, still_there);
  };
  EXPECT_LT(carried(true, false), 0.01);
  EXPECT_GT(carried(false, false), 0.95) << "the scene no longer shows what the check is for";
  EXPECT_GT(carried(true, true), 0.95);
}

// The same at the right border, where the sensor measures nothing (its blind band, and here
// dropouts beside it): once the walker left, the carried box's centre holds no depth at all. It
// masks nothing (before, an empty depth cut fell back to the whole box: a strip of wall and
// band, 30-40 px wide, on the reversed teddy_dyn_crowd_dev).
TEST(FusionOverTime, ACarriedBoxOverTheSensorsBlindBandMasksNothingOnceItsWalkerLeft) {
  const cv::Rect walker(596, 150, 44, 250), band(596, 0, 44, 480);
  Scene gone;
  gone.place(band, 0.f);
  EXPECT_LT(carriedMaskShare(walker, true, gone, false), 0.01);
  EXPECT_GT(carriedMaskShare(walker, false, gone, false), 0.95)
      << "the scene no longer shows what the check is for";
}

TEST(FusionOverTime, OnlyProvenStaticPointsCarveAMovingRegion) {
  // A walker whose depth cut includes a standing person at the same depth: the standing
  // person's points carve it out only when they are proven static (landmarks over time).
  Scene s;
  const cv::Rect walker(200, 150, 60, 250), standing(260, 150, 60, 250);
  s.place(walker, 2.f);
  s.place(standing, 2.f);
  DynamicConfig c;
  const Detection both{cv::Rect2f(190, 140, 140, 270), kPerson, 0.9f};
  FusionEvidence unproven;
  RegionFusion a(c, ClassTable(c));
  const FusionResult ra =
      a.fuse(FusionMode::kBoth, s.depth, s.points, s.flagged(walker), {both}, unproven);
  EXPECT_GT(maskedShare(ra.mask, standing), 0.9);
  FusionEvidence proven;
  proven.proven_static = s.flagged(standing);
  RegionFusion b(c, ClassTable(c));
  const FusionResult rb =
      b.fuse(FusionMode::kBoth, s.depth, s.points, s.flagged(walker), {both}, proven);
  EXPECT_GT(maskedShare(rb.mask, walker), 0.9);
  EXPECT_LT(maskedShare(rb.mask, standing), 0.5);
}

// What the map may judge in hindsight: a person masked only for lack of quiet frames is held
// back; a person masked for flagged points is not; once kept, the person is confirmed.
TEST(FusionOverTime, APersonMaskedOnlyForLackOfQuietFramesIsHeldBackNotOneThatMoved) {
  Scene s;
  const cv::Rect person(200, 150, 80, 250), walker(420, 150, 80, 250);
  s.place(person, 2.f);
  s.place(walker, 2.5f);
  DynamicConfig c;
  c.static_confirm_frames = 3;
  RegionFusion fusion(c, ClassTable(c));
  for (int i = 0; i < 2; ++i) {
    const FusionResult r = fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.flagged(walker),
                                       {box(person), box(walker)});
    EXPECT_GT(maskedShare(r.mask, person), 0.99) << "frame " << i;
    EXPECT_GT(maskedShare(r.held, person), 0.99) << "frame " << i;
    EXPECT_GT(maskedShare(r.mask, walker), 0.99) << "frame " << i;
    EXPECT_LT(maskedShare(r.held, walker), 0.01) << "frame " << i;
    EXPECT_EQ(cv::countNonZero(r.confirmed), 0);
  }
  const FusionResult r = fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.flagged(walker),
                                     {box(person), box(walker)});
  EXPECT_LT(maskedShare(r.mask, person), 0.01);
  EXPECT_GT(maskedShare(r.confirmed, person), 0.99);
  EXPECT_EQ(cv::countNonZero(r.held), 0);
}

}  // namespace
}  // namespace dynamap::fusion_time_test

namespace dynamap::fusion_time_test {
namespace {

TEST(FusionOverTime, APersonWithoutPointsIsKeptWhenItsWorldPositionStaysPut) {
  // A plain jacket: no tracked point on it, so only its world position can tell. Still for
  // static_confirm_frames frames (pose known): kept.
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(4.f));
  const cv::Rect person(300, 150, 80, 250);
  depth(person).setTo(2.5f);
  const std::vector<cv::Point2f> none;
  const std::vector<std::uint8_t> no_flags;
  DynamicConfig c;
  RegionFusion fusion(c, ClassTable(c));
  FusionEvidence ev;
  ev.has_pose = true;
  ev.K = cv::Vec4d(535.4, 539.2, 320.1, 247.6);
  const Detection det{cv::Rect2f(290, 140, 100, 270), 0, 0.9f};
  FusionResult r;
  for (int i = 0; i <= c.static_confirm_frames; ++i)
    r = fusion.fuse(FusionMode::kBoth, depth, none, no_flags, {det}, ev);
  EXPECT_FALSE(r.objects.at(0).moving);
  // Without a pose there is no evidence at all: it stays masked.
  RegionFusion blind(c, ClassTable(c));
  for (int i = 0; i <= 2 * c.static_confirm_frames; ++i)
    r = blind.fuse(FusionMode::kBoth, depth, none, no_flags, {det});
  EXPECT_TRUE(r.objects.at(0).moving);
}

TEST(FusionOverTime, OneObjectWithTwoLabelsTakesItsBetterScoredClass) {
  // The detector calls the teddy "teddy bear" 0.8 and "person" 0.3: it is not a person.
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(4.f));
  const cv::Rect teddy(200, 150, 160, 200);
  depth(teddy).setTo(1.5f);
  DynamicConfig c;
  const ClassTable classes(c);
  RegionFusion fusion(c, classes);
  const Detection bear{cv::Rect2f(190, 140, 180, 220), 77, 0.8f};  // COCO 77 = teddy bear
  const Detection as_person{cv::Rect2f(195, 145, 175, 210), 0, 0.3f};
  ASSERT_FALSE(classes.isHighDynamic(77));
  const FusionResult r = fusion.fuse(FusionMode::kBoth, depth, {}, {}, {bear, as_person});
  ASSERT_EQ(r.objects.size(), 1u);
  EXPECT_EQ(r.objects[0].detection.class_id, 77);
  EXPECT_EQ(cv::countNonZero(r.mask(teddy)), 0);
  // A better-scored person next to a chair is still a person.
  const Detection chair{cv::Rect2f(190, 140, 180, 220), 56, 0.3f};
  const Detection person{cv::Rect2f(195, 145, 175, 210), 0, 0.8f};
  RegionFusion other(c, classes);
  EXPECT_EQ(other.fuse(FusionMode::kBoth, depth, {}, {}, {chair, person}).objects.size(), 2u);
}

// A mover track (a seen-through region, masked while new) that grows over a surface holding
// proven-static landmarks ends there, as a new one would not start: it is the static surface
// the check saw through. Over a surface without them it goes on (masked, then carried).
TEST(FusionOverTime, AMoverTrackEndsWhereItGrowsOverProvenStaticPoints) {
  Scene s;
  const cv::Rect first(200, 200, 160, 160), grown(200, 150, 200, 210);  // IoU .61
  s.place(grown, 1.5f);
  DynamicConfig c;
  const auto mover = [](const cv::Rect& r) {
    return Detection{cv::Rect2f(r), ClassTable::kMover, 1.f};
  };
  const auto run = [&](const std::vector<std::uint8_t>& proven_flags) {
    RegionFusion fusion(c, ClassTable(c));
    FusionResult r = fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.quiet, {mover(first)});
    EXPECT_GT(maskedShare(r.mask, first), 0.9);  // new: masked
    FusionEvidence ev;
    ev.proven_static = proven_flags;
    r = fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.quiet, {mover(grown)}, ev);
    const double grown_share = maskedShare(r.mask, grown);
    r = fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.quiet, {});  // not detected
    return std::make_pair(grown_share, r.objects.size());
  };
  const auto [proven_share, proven_objects] = run(s.flagged(grown));
  EXPECT_LT(proven_share, 0.01);
  EXPECT_EQ(proven_objects, 0u);  // ended, not carried
  const auto [unproven_share, unproven_objects] = run(s.quiet);
  EXPECT_GT(unproven_share, 0.9);
  EXPECT_EQ(unproven_objects, 1u);
}

// The mask's part on moved objects that are not people (FusionResult::moved_objects, what
// mapping's votes reach further beside): a class-less mover's pixels, not a walker's.
TEST(FusionOverTime, MovedObjectsHoldAMoversPixelsNotAPersons) {
  Scene s;
  const cv::Rect person(100, 150, 80, 250), thing(400, 250, 120, 120);
  s.place(person, 2.f);
  s.place(thing, 1.5f);
  DynamicConfig c;
  RegionFusion fusion(c, ClassTable(c));
  const Detection mover{cv::Rect2f(thing), ClassTable::kMover, 1.f};
  const FusionResult r =
      fusion.fuse(FusionMode::kBoth, s.depth, s.points, s.quiet, {box(person), mover});
  EXPECT_GT(maskedShare(r.mask, person), 0.9);  // both new, both masked
  EXPECT_GT(maskedShare(r.mask, thing), 0.9);
  EXPECT_GT(maskedShare(r.moved_objects, thing), 0.9);
  EXPECT_LT(maskedShare(r.moved_objects, person), 0.01);
}

}  // namespace
}  // namespace dynamap::fusion_time_test
