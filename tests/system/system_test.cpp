// dynamap::System without files: input checks, given-pose mapping, errors, borrowed timings.
// (Real-data equality with `dynamap run`: tests/consumer and python/tests.)
#include "dynamap/system.hpp"

#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "dynamap/system/config_schema.hpp"
#include "test_paths.hpp"

namespace dynamap::system_test {
namespace {

AppConfig fastConfig() {
  AppConfig config;
  config.dynamic.mode = "off";
  config.mapping.backend = "points";
  return config;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(System, RejectsImagesOfTheWrongTypeOrSize) {
  System system(fastConfig());
  const cv::Mat bgr(48, 64, CV_8UC3, cv::Scalar::all(0));
  const cv::Mat depth(48, 64, CV_16UC1, cv::Scalar::all(0));
  EXPECT_THROW(system.track(cv::Mat(48, 64, CV_8UC1), depth, 0.0), std::invalid_argument);
  EXPECT_THROW(system.track(bgr, cv::Mat(48, 64, CV_64FC1), 0.0), std::invalid_argument);
  EXPECT_NE(errorOf([&] {
              system.track(bgr, cv::Mat(24, 32, CV_16UC1), 0.0);
            }).find("depth image is 32x24 but colour image is 64x48"),
            std::string::npos);
  EXPECT_EQ(system.counts().frames, 0u);
  EXPECT_TRUE(system.trajectory().empty());
}

TEST(System, TracksAFrameAndReturnsAFrameSizedMask) {
  TimingRecorder timings;
  SystemOptions options;
  options.timings = &timings;
  System system(fastConfig(), std::move(options));
  cv::Mat bgr(480, 640, CV_8UC3);
  cv::randu(bgr, 0, 255);
  const cv::Mat depth(480, 640, CV_32FC1, cv::Scalar::all(1.5));
  const TrackOutput out = system.track(bgr, depth, 12.5);
  EXPECT_TRUE(out.T_W_C.matrix().isIdentity(1e-12));
  EXPECT_EQ(out.dynamic_mask.size(), bgr.size());
  EXPECT_EQ(out.dynamic_mask.type(), CV_8UC1);
  ASSERT_EQ(system.trajectory().size(), 1u);
  EXPECT_DOUBLE_EQ(system.trajectory()[0].timestamp_s, 12.5);
  EXPECT_EQ(&system.timings(), &timings);
  EXPECT_FALSE(timings.allStats().empty());
  system.finish();
  EXPECT_THROW(system.track(bgr, depth, 13.0), std::logic_error);
}

/// Masks a fixed rectangle from the frame with index `from` on: a mover found late.
class LateMaskFilter : public MotionFilter {
 public:
  LateMaskFilter(cv::Rect rect, std::size_t from) : rect_(rect), from_(from) {}
  void beginFrame(const RgbdFrame& frame) override {
    mask_ = cv::Mat::zeros(frame.bgr.size(), CV_8UC1);
    if (frame.index >= from_) mask_(rect_).setTo(255);
  }
  MotionFilterOutput filter(const MotionFilterInput& input) override {
    MotionFilterOutput out;
    out.dynamic_mask = mask_;
    for (const auto& p : input.matches->cur_px) out.match_is_dynamic.push_back(rect_.contains(p));
    return out;
  }

 private:
  cv::Rect rect_;
  std::size_t from_;
  cv::Mat mask_;
};

TEST(System, AKeyframeWaitsForTheMasksOfTheNextFrames) {
  const cv::Rect mover(200, 150, 120, 200);
  cv::Mat bgr(480, 640, CV_8UC3);
  cv::theRNG().state = 7;
  cv::randu(bgr, 0, 255);
  cv::GaussianBlur(bgr, bgr, {5, 5}, 1.0);  // texture that LK can follow
  const cv::Mat depth(480, 640, CV_32FC1, cv::Scalar::all(2.0));
  for (const int lookahead : {0, 2}) {
    AppConfig config = fastConfig();
    config.mapping.mask_lookahead_frames = lookahead;
    SystemOptions options;
    options.motion_filter = std::make_unique<LateMaskFilter>(mover, 1);
    System system(config, std::move(options));
    std::vector<KeyframePacketPtr> mapped;
    for (int i = 0; i < 4; ++i) {
      const TrackOutput out = system.track(bgr, depth, 0.033 * i);
      if (i == 0) {  // the map's first keyframe: no motion evidence, nothing masked
        ASSERT_TRUE(out.is_keyframe);
        EXPECT_EQ(cv::countNonZero(out.keyframe->dynamic_mask), 0);
      }
      mapped.insert(mapped.end(), out.mapped.begin(), out.mapped.end());
      if (lookahead == 0 && i == 0) {
        EXPECT_EQ(out.mapped.size(), 1u);
      }
      if (lookahead == 2 && i < 2) {
        EXPECT_TRUE(out.mapped.empty()) << "frame " << i;
      }
    }
    for (const auto& kf : system.takeLastMapped()) mapped.push_back(kf);
    EXPECT_TRUE(system.takeLastMapped().empty());
    ASSERT_FALSE(mapped.empty());
    ASSERT_EQ(mapped.front()->id, 0u);
    const cv::Mat& mask = mapped.front()->dynamic_mask;
    const int in_rect = mask.empty() ? 0 : cv::countNonZero(mask(mover));
    if (lookahead == 0) {
      EXPECT_EQ(in_rect, 0);
    } else {  // frames 1 and 2 masked the mover: keyframe 0 is masked there, and only there
      EXPECT_GT(in_rect, 0.98 * mover.area());
      EXPECT_EQ(cv::countNonZero(mask) - in_rect, 0);
    }
  }
}

TEST(System, GivenPosesMapEveryFrameAsAKeyframe) {
  SystemOptions options;
  options.given_poses = true;
  System system(fastConfig(), std::move(options));
  RgbdFrame frame;
  frame.bgr = cv::Mat(48, 64, CV_8UC3, cv::Scalar(10, 20, 30));
  frame.depth_m = cv::Mat(48, 64, CV_32FC1, cv::Scalar::all(1.0));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 3; ++i) {
    frame.timestamp_s = i;
    T.translation().x() = 0.1 * i;
    EXPECT_TRUE(system.mapWithPose(frame, T, cv::Mat()).is_keyframe);
  }
  EXPECT_THROW(system.track(frame), std::logic_error);
  const auto dir = test::freshTempDir("system_given_poses");
  system.exportMap(dir.string());
  EXPECT_TRUE(std::filesystem::exists(dir / "cloud.ply"));
  EXPECT_EQ(system.counts().keyframes, 3u);
  EXPECT_EQ(system.counts().mapped_keyframes, 3u);
  ASSERT_EQ(system.keyframes().size(), 3u);
  EXPECT_DOUBLE_EQ(system.keyframes()[2].T_W_C.translation().x(), 0.2);
}

TEST(System, ConfigAndBackendErrorsNameTheProblem) {
  EXPECT_THROW(System::fromConfig("", {"tracking.no_such_key=1"}), ConfigError);
  EXPECT_NE(errorOf([] {
              System::fromConfig("", {"tracking.no_such_key=1"});
            }).find("tracking.no_such_key"),
            std::string::npos);
  AppConfig config = fastConfig();
  config.mapping.backend = "no_such_backend";
  const std::string error = errorOf([&] { System system(config); });
  EXPECT_NE(error.find("no_such_backend"), std::string::npos) << error;
  EXPECT_NE(error.find("pcl_voxel"), std::string::npos) << error;  // lists the known ones
}

}  // namespace
}  // namespace dynamap::system_test
