#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "dynamap/fast_paths/own_pyr_lk.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

namespace fs = std::filesystem;

const cv::Size kWindow(15, 15);

struct Outcome {
  std::vector<cv::Point2f> px;
  std::vector<std::uint8_t> status;
};

/// Both LKs from the same start; the share of points on which they agree: the same status and,
/// where both tracked the point, end positions within 0.01 px.
double agreement(const std::vector<cv::Mat>& prev, const std::vector<cv::Mat>& next,
                 const std::vector<cv::Point2f>& from, const std::vector<cv::Point2f>& guess,
                 int max_level, int iterations) {
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, iterations,
                                  0.01);
  Outcome cv_out{guess, {}}, own{guess, {}};
  cv::calcOpticalFlowPyrLK(prev, next, from, cv_out.px, cv_out.status, cv::noArray(), kWindow,
                           max_level, criteria, cv::OPTFLOW_USE_INITIAL_FLOW);
  lk::ownPyrLk(prev, next, from, own.px, own.status, kWindow, max_level, criteria);
  std::size_t agree = 0;
  for (std::size_t i = 0; i < from.size(); ++i) {
    const bool cv_ok = cv_out.status[i] != 0, own_ok = own.status[i] != 0;
    agree += cv_ok == own_ok && (!cv_ok || cv::norm(cv_out.px[i] - own.px[i]) <= 0.01);
  }
  return static_cast<double>(agree) / static_cast<double>(from.size());
}

/// The tolerance: 99.9 % of the points agree (float rounding may send an odd point elsewhere).
constexpr double kMinAgreement = 0.999;

std::vector<cv::Mat> pyramidOf(const cv::Mat& gray, int max_level) {
  std::vector<cv::Mat> pyramid;
  cv::buildOpticalFlowPyramid(gray, pyramid, kWindow, max_level, true);
  return pyramid;
}

/// Points on features, on a grid (flat areas, the border, outside it) and at random positions.
std::vector<cv::Point2f> testPoints(const cv::Mat& gray, cv::RNG& rng) {
  std::vector<cv::Point2f> pts;
  cv::goodFeaturesToTrack(gray, pts, 400, 0.01, 8);
  for (int y = -20; y < gray.rows + 20; y += 23) {
    for (int x = -20; x < gray.cols + 20; x += 29) pts.emplace_back(x + 0.37f, y + 0.61f);
  }
  for (int i = 0; i < 300; ++i) {
    pts.emplace_back(rng.uniform(0.f, static_cast<float>(gray.cols - 1)),
                     rng.uniform(0.f, static_cast<float>(gray.rows - 1)));
  }
  return pts;
}

std::vector<cv::Point2f> guesses(const std::vector<cv::Point2f>& from, cv::RNG& rng, float spread) {
  std::vector<cv::Point2f> out;
  for (const auto& p : from) {
    out.emplace_back(p.x + rng.uniform(-spread, spread), p.y + rng.uniform(-spread, spread));
  }
  return out;
}

TEST(OwnPyrLk, AgreesWithOpenCvOnAShiftedTexture) {
  if (!lk::ownPyrLkUsable(kWindow)) GTEST_SKIP() << "own LK not usable here (CPU without AVX2)";
  cv::RNG rng(7);
  cv::Mat noise(480, 640, CV_8UC1);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  cv::Mat gray;
  cv::GaussianBlur(noise, gray, {0, 0}, 2.5);
  cv::normalize(gray, gray, 0, 255, cv::NORM_MINMAX);
  cv::Mat shifted;
  cv::warpAffine(gray, shifted, cv::Matx23d(1, 0, 6.3, 0, 1, -3.7), gray.size(), cv::INTER_CUBIC,
                 cv::BORDER_REFLECT);
  const std::vector<cv::Point2f> from = testPoints(gray, rng);
  for (const int levels : {0, 2, 4}) {
    const auto prev = pyramidOf(gray, levels), next = pyramidOf(shifted, levels);
    for (const int iterations : {1, 5, 20}) {
      EXPECT_GE(agreement(prev, next, from, from, levels, iterations), kMinAgreement)
          << "levels " << levels << ", iterations " << iterations;
      EXPECT_GE(agreement(prev, next, from, guesses(from, rng, 12.f), levels, iterations),
                kMinAgreement)
          << "levels " << levels << ", iterations " << iterations << ", noisy guesses";
    }
  }
}

TEST(OwnPyrLk, AgreesWithOpenCvOnRealFrames) {
  if (!lk::ownPyrLkUsable(kWindow)) GTEST_SKIP() << "own LK not usable here (CPU without AVX2)";
  DYNAMAP_REQUIRE_SHARED_DATA();
  for (const char* seq : {"dynamic/teddy_dyn_crowd_dev", "bonn/rgbd_bonn_crowd_400_499"}) {
    std::vector<fs::path> frames;
    for (const auto& e : fs::directory_iterator(test::sharedData() / seq / "rgb")) {
      frames.push_back(e.path());
    }
    std::sort(frames.begin(), frames.end());
    ASSERT_GE(frames.size(), 60u) << seq;
    cv::RNG rng(11);
    for (const std::size_t i : {std::size_t{0}, std::size_t{25}, std::size_t{55}}) {
      cv::Mat a, b;
      cv::cvtColor(cv::imread(frames[i].string()), a, cv::COLOR_BGR2GRAY);
      cv::cvtColor(cv::imread(frames[i + 3].string()), b, cv::COLOR_BGR2GRAY);
      const auto prev = pyramidOf(a, 5), next = pyramidOf(b, 5);
      const std::vector<cv::Point2f> from = testPoints(a, rng);
      EXPECT_GE(agreement(prev, next, from, guesses(from, rng, 4.f), 5, 20), kMinAgreement)
          << frames[i] << " forward";
      EXPECT_GE(agreement(next, prev, from, from, 2, 20), kMinAgreement) << frames[i] << " backward";
    }
  }
}

TEST(OwnPyrLk, IsUsableOnlyForItsWindowWidth) {
  EXPECT_FALSE(lk::ownPyrLkUsable({21, 21}));
  EXPECT_FALSE(lk::ownPyrLkUsable({9, 9}));
}

}  // namespace
}  // namespace dynamap
