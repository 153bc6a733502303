#include <cstdint>

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "dynamap/core/tracking/lk_tracker.hpp"
#include "synthetic_scene.hpp"

namespace dynamap {
namespace {

/// A textured plane seen by the freiburg3 camera (`seed` picks the texture) and the same image
/// shifted by `shift` pixels.
struct ShiftedPair {
  cv::Mat gray, shifted;
};

ShiftedPair texturedPlaneShifted(std::uint64_t seed, const cv::Point2f& shift) {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, seed);
  scene.addPlane({-2.0, -1.5, 1.5}, {4.0, 0, 0}, {0, 3.0, 0});
  const auto frame = scene.render(Eigen::Isometry3d::Identity(), 0.0);
  ShiftedPair pair;
  cv::cvtColor(frame.bgr, pair.gray, cv::COLOR_BGR2GRAY);
  const cv::Matx23d M(1, 0, shift.x, 0, 1, shift.y);
  cv::warpAffine(pair.gray, pair.shifted, M, pair.gray.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  return pair;
}

TEST(LkTracker, TracksKnownSubPixelShift) {
  const cv::Point2f shift(7.35f, -4.6f);
  const ShiftedPair pair = texturedPlaneShifted(5, shift);
  const cv::Mat &gray = pair.gray, &shifted = pair.shifted;

  std::vector<cv::Point2f> prev_px;
  cv::goodFeaturesToTrack(gray, prev_px, 300, 0.01, 15);
  std::vector<cv::Point2f> kept;
  for (const auto& p : prev_px) {
    if (p.x > 40 && p.y > 40 && p.x < gray.cols - 40 && p.y < gray.rows - 40) kept.push_back(p);
  }
  ASSERT_GT(kept.size(), 100u);

  TrackerConfig config;
  const LkTracker lk(config);
  const LkPyramid a = lk.buildPyramid(gray), b = lk.buildPyramid(shifted);
  std::vector<cv::Point2f> cur_px = kept;  // no prior: LK must find the whole shift
  std::vector<std::uint8_t> ok;
  lk.track(a, b, kept, cur_px, ok);
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    if (!ok[i]) continue;
    sum += cv::norm(cur_px[i] - (kept[i] + shift));
    ++n;
  }
  EXPECT_GT(n, static_cast<int>(0.9 * kept.size()));
  EXPECT_LT(sum / n, 0.1);
}

TEST(LkTracker, ForwardBackwardCheckRejectsUntrackablePoints) {
  TrackerConfig config;
  const LkTracker lk(config);
  cv::Mat flat(480, 640, CV_8UC1, cv::Scalar(128));
  const LkPyramid a = lk.buildPyramid(flat), b = lk.buildPyramid(flat);
  std::vector<cv::Point2f> prev_px{{100, 100}, {320, 240}}, cur_px = prev_px;
  std::vector<std::uint8_t> ok;
  lk.track(a, b, prev_px, cur_px, ok);
  EXPECT_EQ(ok[0] + ok[1], 0);
}

TEST(LkTracker, TwoThreadsTrackEveryPointAsOneDoes) {
  const ShiftedPair pair = texturedPlaneShifted(7, {3.2f, 1.7f});
  const cv::Mat &gray = pair.gray, &moved = pair.shifted;
  std::vector<cv::Point2f> prev_px;
  cv::goodFeaturesToTrack(gray, prev_px, 400, 0.01, 8);
  ASSERT_GT(prev_px.size(), 200u);

  TrackerConfig one, two;
  one.lk_threads = 1;
  two.lk_threads = 2;
  const LkPyramid a = LkTracker(one).buildPyramid(gray), b = LkTracker(one).buildPyramid(moved);
  std::vector<cv::Point2f> px_one = prev_px, px_two = prev_px;
  std::vector<std::uint8_t> ok_one, ok_two;
  LkTracker(one).track(a, b, prev_px, px_one, ok_one);
  LkTracker(two).track(a, b, prev_px, px_two, ok_two);
  ASSERT_EQ(ok_two.size(), ok_one.size());
  for (std::size_t i = 0; i < prev_px.size(); ++i) {
    EXPECT_EQ(ok_two[i], ok_one[i]) << i;
    EXPECT_EQ(px_two[i], px_one[i]) << i;  // bit for bit
  }
}

// The backward (consistency) pass starts from the point's own position, so a few levels do: the
// forward answers stay bit for bit, a shift too large for 3 levels (41 px) still passes, and an
// untrackable point fails.
TEST(LkTracker, BackwardPassOverFewLevelsKeepsTheForwardAnswerAndTheCheck) {
  const ShiftedPair pair = texturedPlaneShifted(11, {41.3f, -22.7f});
  std::vector<cv::Point2f> prev_px;
  cv::goodFeaturesToTrack(pair.gray, prev_px, 300, 0.01, 12);
  std::vector<cv::Point2f> inner;
  for (const auto& p : prev_px) {
    if (p.x > 60 && p.y > 60 && p.x < pair.gray.cols - 60 && p.y < pair.gray.rows - 60)
      inner.push_back(p);
  }
  ASSERT_GT(inner.size(), 100u);
  inner.push_back({320.f, 240.f});  // the last point lies on a blank patch (below)
  cv::Mat gray = pair.gray.clone(), moved = pair.shifted.clone();
  gray(cv::Rect(290, 210, 60, 60)).setTo(128);
  moved(cv::Rect(290, 210, 60, 60)).setTo(128);

  const TrackerConfig config;
  const LkTracker lk(config);
  const LkPyramid a = lk.buildPyramid(gray), b = lk.buildPyramid(moved);
  std::vector<cv::Point2f> px_all = inner, px_few = inner;
  std::vector<std::uint8_t> ok_all, ok_few;
  lk.track(a, b, inner, px_all, ok_all);
  lk.track(a, b, inner, px_few, ok_few, 3);
  int agree = 0, passed = 0, passed_all = 0;
  for (std::size_t i = 0; i < inner.size(); ++i) {
    EXPECT_EQ(px_few[i], px_all[i]) << i;  // the forward pass is the same
    agree += ok_few[i] == ok_all[i];
    passed += ok_few[i];
    passed_all += ok_all[i];
  }
  // Nearly the same verdicts, and most tracks of the textured plane pass (the 41 px shift is
  // at the edge of what the window finds: 84 % pass with all levels in the clang sanitizer
  // build, 94 % with gcc).
  EXPECT_GE(agree, static_cast<int>(0.97 * inner.size()));
  EXPECT_GE(passed, static_cast<int>(0.75 * (inner.size() - 1))) << passed_all;
  EXPECT_EQ(ok_few.back(), 0);  // blank: no consistent track
}

}  // namespace
}  // namespace dynamap
