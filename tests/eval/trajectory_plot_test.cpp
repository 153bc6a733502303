#include "trajectory_plot.hpp"

#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "test_paths.hpp"

namespace dynamap {
namespace {

std::vector<TimedPose> circle(double radius, double z_offset, double t0) {
  std::vector<TimedPose> poses;
  for (int k = 0; k < 300; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    const double a = 2.0 * M_PI * k / 300.0;
    T.translation() = Eigen::Vector3d(radius * std::cos(a), z_offset + 0.05 * std::sin(3 * a),
                                      radius * std::sin(a));
    poses.push_back({t0 + k / 30.0, T});
  }
  return poses;
}

/// Number of strongly coloured (non-grey) pixels: the error-coloured estimate and colour bar.
int colouredPixels(const cv::Mat& img) {
  int n = 0;
  for (auto it = img.begin<cv::Vec3b>(); it != img.end<cv::Vec3b>(); ++it) {
    const int lo = std::min({(*it)[0], (*it)[1], (*it)[2]});
    const int hi = std::max({(*it)[0], (*it)[1], (*it)[2]});
    n += hi - lo > 60;
  }
  return n;
}

TEST(TrajectoryPlot, RendersAndWritesAtomically) {
  const auto gt = circle(1.0, 0.0, 0.0);
  auto est = circle(1.02, 0.01, 0.0);
  const AteResult ate = computeAte(gt, est, TrajectoryEvalOptions{});
  const cv::Mat img = renderTrajectoryPlot(gt, ate);
  ASSERT_EQ(img.size(), cv::Size(1000, 800));
  ASSERT_EQ(img.type(), CV_8UC3);
  // Colour bar alone is ~28 x 600 coloured pixels; the estimate adds more.
  EXPECT_GT(colouredPixels(img), 28 * 500);
  // The plot centre (inside the circle) holds only background and grid lines (no path).
  double lo = 0.0;
  cv::Mat centre_grey;
  cv::cvtColor(img(cv::Rect(450, 385, 40, 40)), centre_grey, cv::COLOR_BGR2GRAY);
  cv::minMaxLoc(centre_grey, &lo);
  EXPECT_GE(lo, 200.0);

  const auto dir = test::freshTempDir("plot");
  const std::string path = (dir / "traj.png").string();
  writeTrajectoryPlot(path, gt, ate);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  const cv::Mat back = cv::imread(path, cv::IMREAD_COLOR);
  ASSERT_FALSE(back.empty());
  EXPECT_EQ(cv::norm(back, img, cv::NORM_INF), 0.0);
  EXPECT_THROW(writeTrajectoryPlot((dir / "missing" / "x.png").string(), gt, ate),
               std::runtime_error);
}

}  // namespace
}  // namespace dynamap
