// checkRigidMotion() with a prior motion (core/src/dynamic/rigid_check.cpp, the path the motion
// filter takes when the tracker's map gives the camera motion): a rigid mover holding most of the
// matches out-votes the background in RANSAC, the true prior keeps the background; a wrong prior
// that too few matches agree with is not taken.
#include <gtest/gtest.h>

#include <algorithm>

#include <opencv2/calib3d.hpp>

#include "dynamap/core/dynamic/epipolar_check.hpp"

namespace dynamap::rigid_prior_test {
namespace {

const cv::Vec4d kK(500, 500, 320, 240);

cv::Point2f project(const cv::Vec3d& p) {
  return {static_cast<float>(500 * p[0] / p[2] + 320), static_cast<float>(500 * p[1] / p[2] + 240)};
}

/// Two views of a static cloud and of one rigid mover (all its points translated by the same
/// 15 cm between the views), the current depth as 7x7 patches around each current pixel.
struct Scene {
  std::vector<cv::Point2f> prev_px, cur_px;
  std::vector<bool> moving;
  cv::Mat depth;
  RigidMotion truth;  ///< current -> previous camera, as checkRigidMotion() reports it
};

Scene makeScene(int n_static, int n_moving, std::uint64_t seed) {
  cv::RNG rng(seed);
  Scene s;
  cv::Matx33d R;
  cv::Rodrigues(cv::Vec3d(0.01, 0.035, -0.005), R);
  const cv::Vec3d t(0.12, 0.02, 0.03);  // X_cur = R X_prev + t
  cv::Rodrigues(cv::Mat(R.t()), s.truth.rvec);
  s.truth.tvec = -(R.t() * t);
  s.truth.valid = true;
  const cv::Vec3d mover_shift(-0.15, 0.0, 0.02);
  s.depth = cv::Mat::zeros(480, 640, CV_32F);
  std::vector<double> cur_depth;
  for (int i = 0; i < n_static + n_moving; ++i) {
    const bool moving = i >= n_static;
    const double z = moving ? rng.uniform(1.5, 2.5) : rng.uniform(3.0, 6.0);
    const cv::Vec3d X0((rng.uniform(20.0, 620.0) - 320) * z / 500,
                       (rng.uniform(20.0, 460.0) - 240) * z / 500, z);
    const cv::Vec3d X1 = R * (moving ? X0 + mover_shift : X0) + t;
    const auto noise = [&] {
      return cv::Point2f(static_cast<float>(rng.gaussian(0.2)),
                         static_cast<float>(rng.gaussian(0.2)));
    };
    s.prev_px.push_back(project(X0) + noise());
    s.cur_px.push_back(project(X1) + noise());
    s.moving.push_back(moving);
    cur_depth.push_back(X1[2]);
  }
  // Far points drawn first: a near mover's patch covers the background's, as a camera sees it.
  std::vector<int> order(cur_depth.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return cur_depth[a] > cur_depth[b]; });
  for (int i : order) {
    const cv::Rect patch(cvRound(s.cur_px[i].x) - 3, cvRound(s.cur_px[i].y) - 3, 7, 7);
    s.depth(patch & cv::Rect(0, 0, 640, 480)).setTo(cur_depth[static_cast<std::size_t>(i)]);
  }
  return s;
}

struct Rates {
  double moving = 0.0, stat = 0.0;
};

Rates flagRates(const Scene& s, const EpipolarResult& r) {
  int mf = 0, mn = 0, sf = 0, sn = 0;
  for (std::size_t i = 0; i < s.moving.size(); ++i) {
    (s.moving[i] ? mn : sn)++;
    (s.moving[i] ? mf : sf) += r.is_dynamic[i] ? 1 : 0;
  }
  return {double(mf) / mn, double(sf) / sn};
}

double translationGap(const RigidMotion& a, const RigidMotion& b) {
  return cv::norm(a.tvec - b.tvec);
}

// 35 % background, 65 % one rigid mover.
constexpr int kStatic = 140, kMoving = 260;

TEST(RigidCheckPrior, TheTruePriorKeepsTheBackgroundAgainstAMovingMajority) {
  const Scene s = makeScene(kStatic, kMoving, 21);
  const EpipolarOptions options;

  // Without a prior the mover's motion wins the vote: the background is flagged.
  RigidMotion voted;
  const EpipolarResult r0 = checkRigidMotion(s.prev_px, s.cur_px, s.depth, kK, {}, options, &voted);
  ASSERT_EQ(r0.model, EpipolarModel::kRigid);
  EXPECT_FALSE(r0.from_prior);
  const Rates f0 = flagRates(s, r0);
  EXPECT_GE(f0.stat, 0.8) << "the premise: RANSAC alone takes the mover for the background";

  // With the true motion as the prior it is taken (and refined): movers flagged, background not.
  RigidMotion estimated;
  const EpipolarResult r =
      checkRigidMotion(s.prev_px, s.cur_px, s.depth, kK, {}, options, &estimated, &s.truth);
  ASSERT_EQ(r.model, EpipolarModel::kRigid);
  EXPECT_TRUE(r.from_prior);
  const Rates f = flagRates(s, r);
  EXPECT_GE(f.moving, 0.9);
  EXPECT_LE(f.stat, 0.05);
  ASSERT_TRUE(estimated.valid);
  EXPECT_LT(translationGap(estimated, s.truth), 0.01);        // refined within 1 cm of the truth
  EXPECT_LT(cv::norm(estimated.rvec - s.truth.rvec), 0.005);  // and 0.3 degrees
}

TEST(RigidCheckPrior, APriorNearTheTruthIsRefinedOntoIt) {
  const Scene s = makeScene(kStatic, kMoving, 22);
  // 5 mm and 0.06 degrees off: the background still agrees with it within the fit's 2 px.
  RigidMotion prior = s.truth;
  prior.tvec += cv::Vec3d(0.004, -0.003, 0.0);
  prior.rvec += cv::Vec3d(0.0, 0.001, 0.0);
  RigidMotion estimated;
  const EpipolarResult r =
      checkRigidMotion(s.prev_px, s.cur_px, s.depth, kK, {}, EpipolarOptions{}, &estimated, &prior);
  EXPECT_TRUE(r.from_prior);
  ASSERT_TRUE(estimated.valid);
  EXPECT_LT(translationGap(estimated, s.truth), 0.6 * translationGap(prior, s.truth));
  EXPECT_LE(flagRates(s, r).stat, 0.05);
}

TEST(RigidCheckPrior, APriorTooFewMatchesAgreeWithIsNotTaken) {
  // Mostly background now (80 %); the prior is 30 cm off: fewer than a fifth of the fit matches
  // agree with it, so RANSAC decides, and finds the background.
  const Scene s = makeScene(320, 80, 23);
  RigidMotion wrong = s.truth;
  wrong.tvec += cv::Vec3d(0.3, 0.0, 0.0);
  RigidMotion estimated;
  const EpipolarResult r =
      checkRigidMotion(s.prev_px, s.cur_px, s.depth, kK, {}, EpipolarOptions{}, &estimated, &wrong);
  ASSERT_EQ(r.model, EpipolarModel::kRigid);
  EXPECT_FALSE(r.from_prior);
  ASSERT_TRUE(estimated.valid);
  EXPECT_LT(translationGap(estimated, s.truth), 0.01);
  const Rates f = flagRates(s, r);
  EXPECT_GE(f.moving, 0.9);
  EXPECT_LE(f.stat, 0.05);

  // An invalid prior is no prior.
  RigidMotion invalid = s.truth;
  invalid.valid = false;
  EXPECT_FALSE(
      checkRigidMotion(s.prev_px, s.cur_px, s.depth, kK, {}, EpipolarOptions{}, nullptr, &invalid)
          .from_prior);
}

}  // namespace
}  // namespace dynamap::rigid_prior_test
