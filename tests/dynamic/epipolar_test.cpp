#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include "dynamap/core/dynamic/epipolar_check.hpp"

namespace dynamap {
namespace {

const cv::Matx33d kK(500, 0, 320, 0, 500, 240, 0, 0, 1);

cv::Point2f project(const cv::Vec3d& p) {
  return {static_cast<float>(500 * p[0] / p[2] + 320), static_cast<float>(500 * p[1] / p[2] + 240)};
}

/// Two views of a static point cloud plus a group of points that moved between the views.
struct TwoViews {
  std::vector<cv::Point2f> prev_px, cur_px;
  std::vector<double> cur_depth;
  std::vector<bool> moving;
  cv::Matx33d R;
  cv::Vec3d t;  ///< X_cur = R X_prev + t
};

TwoViews makeViews(int n_static, int n_moving, double noise_px, std::uint64_t seed) {
  cv::RNG rng(seed);
  TwoViews v;
  cv::Rodrigues(cv::Vec3d(0.01, 0.035, -0.005), v.R);
  v.t = cv::Vec3d(0.12, 0.02, 0.03);
  for (int i = 0; i < n_static + n_moving; ++i) {
    const double z = rng.uniform(1.5, 6.0);
    const cv::Vec3d X0((rng.uniform(20.0, 620.0) - 320) * z / 500,
                       (rng.uniform(20.0, 460.0) - 240) * z / 500, z);
    cv::Vec3d X0_moved = X0;
    const bool moving = i >= n_static;
    if (moving) {  // 8-15 cm in a random direction
      cv::Vec3d d(rng.gaussian(1), rng.gaussian(1), rng.gaussian(1));
      X0_moved += d * (rng.uniform(0.08, 0.15) / cv::norm(d));
    }
    const cv::Vec3d X1 = v.R * X0_moved + v.t;
    cv::Point2f p0 = project(X0), p1 = project(X1);
    p0 += cv::Point2f(static_cast<float>(rng.gaussian(noise_px)),
                      static_cast<float>(rng.gaussian(noise_px)));
    p1 += cv::Point2f(static_cast<float>(rng.gaussian(noise_px)),
                      static_cast<float>(rng.gaussian(noise_px)));
    v.prev_px.push_back(p0);
    v.cur_px.push_back(p1);
    v.cur_depth.push_back(X1[2]);
    v.moving.push_back(moving);
  }
  return v;
}

struct FlagRates {
  double moving = 0.0, stat = 0.0;
};

FlagRates rates(const TwoViews& v, const std::vector<std::uint8_t>& flags) {
  int mf = 0, mn = 0, sf = 0, sn = 0;
  for (std::size_t i = 0; i < v.moving.size(); ++i) {
    (v.moving[i] ? mn : sn)++;
    (v.moving[i] ? mf : sf) += flags[i] ? 1 : 0;
  }
  return {mn ? double(mf) / mn : 0.0, sn ? double(sf) / sn : 0.0};
}

TEST(EpipolarCheck, KnownFundamentalMatrixHasZeroDistanceOnStaticPoints) {
  const TwoViews v = makeViews(50, 0, 0.0, 1);
  const cv::Matx33d tx(0, -v.t[2], v.t[1], v.t[2], 0, -v.t[0], -v.t[1], v.t[0], 0);
  const cv::Matx33d F = kK.inv().t() * tx * v.R * kK.inv();
  for (std::size_t i = 0; i < v.prev_px.size(); ++i) {
    EXPECT_LT(symmetricEpipolarDistance(F, v.prev_px[i], v.cur_px[i]), 1e-3);
  }
}

TEST(EpipolarCheck, FlagsMovingPointsAndNotStaticOnes) {
  const TwoViews v = makeViews(300, 40, 0.2, 2);
  const EpipolarResult r = checkEpipolar(v.prev_px, v.cur_px, EpipolarOptions{});
  ASSERT_EQ(r.model, EpipolarModel::kFundamental);
  const FlagRates f = rates(v, r.is_dynamic);
  // A point moving along its own epipolar line is invisible to this check: some escape.
  EXPECT_GE(f.moving, 0.7);
  EXPECT_LE(f.stat, 0.05);
}

TEST(EpipolarCheck, DegenerateInputsFlagNothing) {
  const TwoViews few = makeViews(12, 3, 0.2, 3);
  const EpipolarResult r1 = checkEpipolar(few.prev_px, few.cur_px, EpipolarOptions{});
  EXPECT_EQ(r1.model, EpipolarModel::kNone);
  EXPECT_EQ(std::count(r1.is_dynamic.begin(), r1.is_dynamic.end(), 1), 0);

  TwoViews still = makeViews(200, 20, 0.0, 4);
  still.cur_px = still.prev_px;  // no camera motion, nothing moved
  const EpipolarResult r2 = checkEpipolar(still.prev_px, still.cur_px, EpipolarOptions{});
  EXPECT_EQ(r2.model, EpipolarModel::kNone);
  EXPECT_EQ(std::count(r2.is_dynamic.begin(), r2.is_dynamic.end(), 1), 0);
}

TEST(EpipolarCheck, PureRotationUsesHomographyAndStillFindsMovers) {
  TwoViews v = makeViews(300, 40, 0.2, 5);
  // Re-create the current view with a pure rotation (F is ill-conditioned).
  cv::RNG rng(6);
  for (std::size_t i = 0; i < v.prev_px.size(); ++i) {
    const cv::Vec3d ray((v.prev_px[i].x - 320) / 500.0, (v.prev_px[i].y - 240) / 500.0, 1.0);
    cv::Point2f p = project(v.R * ray);
    if (v.moving[i])
      p += cv::Point2f(rng.uniform(-1.f, 1.f) * 4 + 6, rng.uniform(-1.f, 1.f) * 4 - 6);
    v.cur_px[i] = p + cv::Point2f(static_cast<float>(rng.gaussian(0.2)),
                                  static_cast<float>(rng.gaussian(0.2)));
  }
  const EpipolarResult r = checkEpipolar(v.prev_px, v.cur_px, EpipolarOptions{});
  EXPECT_EQ(r.model, EpipolarModel::kHomography);
  const FlagRates f = rates(v, r.is_dynamic);
  EXPECT_GE(f.moving, 0.9);
  EXPECT_LE(f.stat, 0.05);
}

TEST(RigidCheck, DepthMakesTheCheckSeeMotionAlongEpipolarLines) {
  const TwoViews v = makeViews(300, 40, 0.2, 7);
  cv::Mat depth = cv::Mat::zeros(480, 640, CV_32F);
  for (std::size_t i = 0; i < v.cur_px.size(); ++i) {
    const cv::Rect patch(cvRound(v.cur_px[i].x) - 3, cvRound(v.cur_px[i].y) - 3, 7, 7);
    depth(patch & cv::Rect(0, 0, 640, 480)).setTo(v.cur_depth[i]);
  }
  RigidMotion motion;
  const EpipolarResult r = checkRigidMotion(
      v.prev_px, v.cur_px, depth, cv::Vec4d(500, 500, 320, 240), {}, EpipolarOptions{}, &motion);
  ASSERT_EQ(r.model, EpipolarModel::kRigid);
  const FlagRates f = rates(v, r.is_dynamic);
  EXPECT_GE(f.moving, 0.85);  // overlapping depth patches can give a few points a wrong depth
  EXPECT_LE(f.stat, 0.05);
  // The estimated motion maps current points to the previous frame: the inverse of (R, t).
  ASSERT_TRUE(motion.valid);
  EXPECT_NEAR(cv::norm(motion.tvec + cv::Vec3d(v.R.t() * v.t)), 0.0, 0.01);
}

TEST(RigidCheck, BlankDepthFallsBackToTheEpipolarCheck) {
  // A colour frame with no depth (none recorded near it, or a blank image): every point would
  // look "far"; the check must not fit a rigid motion to 12 m points but use F instead.
  const TwoViews v = makeViews(300, 40, 0.2, 11);
  const cv::Mat blank = cv::Mat::zeros(480, 640, CV_32F);
  const EpipolarResult r = checkRigidMotion(v.prev_px, v.cur_px, blank,
                                            cv::Vec4d(500, 500, 320, 240), {}, EpipolarOptions{});
  EXPECT_NE(r.model, EpipolarModel::kRigid);
  const FlagRates f = rates(v, r.is_dynamic);
  EXPECT_LE(f.stat, 0.05);
}

}  // namespace
}  // namespace dynamap
