// Fault injection on the `dynamap` program (issue 7): a bad detector model is one clear error
// before any frame; frames without depth and long stretches where tracking must fail end in a
// complete run whose run.json counts them. Never a crash.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli_test_util.hpp"
#include "json_io.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

namespace fs = std::filesystem;
using test::runDynamap;

const fs::path kYoloDir = test::sharedModels() / "yolo-fastest";

/// Image files listed in a TUM list file (relative to the sequence folder), in order.
std::vector<std::string> listedFiles(const fs::path& list_path) {
  std::ifstream in(list_path);
  std::vector<std::string> files;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    files.push_back(line.substr(line.find(' ') + 1));
  }
  return files;
}

/// Replaces (the symlink of) `file` in `seq` by `image`.
void overwriteImage(const fs::path& seq, const std::string& file, const cv::Mat& image) {
  fs::remove(seq / file);
  ASSERT_TRUE(cv::imwrite((seq / file).string(), image)) << file;
}

/// A run on `seq` with the fast settings (geometry only, raw points).
test::CommandResult runFast(const fs::path& seq, const fs::path& out) {
  return runDynamap({"run", "--sequence", seq.string(), "--out", out.string(), "--set",
                     "dynamic.mode=geometry", "--set", "mapping.backend=points", "--quiet"});
}

/// run.json's "counts" member `key` (-1 when absent).
double count(const Json& run, const std::string& key) {
  const Json* counts = findMember(run, "counts");
  if (counts == nullptr) return -1;
  return numberMember(*counts, key).value_or(-1);
}

/// Runs the detector mode with the given model overrides on 3 frames: the run must stop before
/// any frame with an error naming `expect_in_error`.
void expectModelErrorBeforeFirstFrame(const std::string& name,
                                      const std::vector<std::string>& model_overrides,
                                      const std::string& expect_in_error) {
  const std::string seq = test::makeTeddySubset(name, 3);
  const fs::path out = test::freshTempDir(name + "_out");
  std::vector<std::string> args = {
      "run", "--sequence", seq, "--out", out.string(), "--set", "dynamic.mode=detector", "--quiet"};
  for (const std::string& o : model_overrides) {
    args.push_back("--set");
    args.push_back(o);
  }
  const auto r = runDynamap(args);
  EXPECT_NE(r.exit_code, 0) << r.out;
  EXPECT_LT(r.exit_code, 128) << "killed by a signal: " << r.err;
  EXPECT_NE(r.err.find(expect_in_error), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "trajectory.txt"));
  if (fs::exists(out / "run.json")) {
    const Json run = readJsonFile((out / "run.json").string());
    EXPECT_EQ(count(run, "frames_read"), 0.0);
    EXPECT_EQ(stringMember(run, "status").value_or(""), "failed");
  }
}

TEST(FaultInjection, MissingDetectorWeightsFailBeforeAnyFrame) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  expectModelErrorBeforeFirstFrame(
      "fault_noweights",
      {"dynamic.model_cfg=" + (kYoloDir / "yolo-fastest-1.1-xl.cfg").string(),
       "dynamic.model_weights=/nonexistent/model.weights"},
      "/nonexistent/model.weights");
}

TEST(FaultInjection, MissingDetectorCfgFailsBeforeAnyFrame) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  expectModelErrorBeforeFirstFrame(
      "fault_nocfg",
      {"dynamic.model_cfg=/nonexistent/model.cfg",
       "dynamic.model_weights=" + (kYoloDir / "yolo-fastest-1.1-xl.weights").string()},
      "/nonexistent/model.cfg");
}

TEST(FaultInjection, WeightsOfTheWrongFormatFailBeforeAnyFrame) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const fs::path dir = test::freshTempDir("fault_badmodels");
  std::ofstream(dir / "text.weights") << "this is not a darknet weights file\n";
  std::ofstream(dir / "text.onnx") << "neither is this an onnx graph\n";
  std::ofstream(dir / "bad.cfg") << "[net]\nwidth=abc\n[convolutional]\nfilters=oops\n";
  expectModelErrorBeforeFirstFrame(
      "fault_textweights",
      {"dynamic.model_cfg=" + (kYoloDir / "yolo-fastest-1.1-xl.cfg").string(),
       "dynamic.model_weights=" + (dir / "text.weights").string()},
      (dir / "text.weights").string());
  expectModelErrorBeforeFirstFrame(
      "fault_badcfg",
      {"dynamic.model_cfg=" + (dir / "bad.cfg").string(),
       "dynamic.model_weights=" + (kYoloDir / "yolo-fastest-1.1-xl.weights").string()},
      (dir / "bad.cfg").string());
  for (const char* detector : {"yolov8_onnx", "nanodet_onnx"}) {
    expectModelErrorBeforeFirstFrame(std::string("fault_textonnx_") + detector,
                                     {std::string("dynamic.detector=") + detector,
                                      "dynamic.model_weights=" + (dir / "text.onnx").string()},
                                     (dir / "text.onnx").string());
  }
}

// OpenCV's Darknet reader does not check for short reads; the detector compares the file
// size with the network's parameter count (core/src/dynamic/detector_nets.cpp).
TEST(FaultInjection, TruncatedDarknetWeightsFailBeforeAnyFrame) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const fs::path dir = test::freshTempDir("fault_truncweights");
  {
    std::ifstream in(kYoloDir / "yolo-fastest-1.1-xl.weights", std::ios::binary);
    std::vector<char> head(100000);
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    std::ofstream(dir / "trunc.weights", std::ios::binary).write(head.data(), in.gcount());
  }
  expectModelErrorBeforeFirstFrame(
      "fault_truncweights_run",
      {"dynamic.model_cfg=" + (kYoloDir / "yolo-fastest-1.1-xl.cfg").string(),
       "dynamic.model_weights=" + (dir / "trunc.weights").string()},
      (dir / "trunc.weights").string());
}

TEST(FaultInjection, AllZeroDepthFramesAreTrackedAndCounted) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  constexpr std::size_t kFrames = 30;
  const fs::path seq = test::makeTeddySubset("fault_zerodepth", kFrames);
  const auto depth_files = listedFiles(seq / "depth.txt");
  ASSERT_GE(depth_files.size(), 25u);
  const cv::Mat zeros = cv::Mat::zeros(480, 640, CV_16UC1);
  for (std::size_t i = 10; i < 20; ++i) overwriteImage(seq, depth_files[i], zeros);
  const fs::path out = test::freshTempDir("fault_zerodepth_out");
  const auto r = runFast(seq, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json run = readJsonFile((out / "run.json").string());
  EXPECT_EQ(stringMember(run, "status").value_or(""), "complete");
  EXPECT_EQ(count(run, "frames_read"), static_cast<double>(kFrames));
  EXPECT_EQ(count(run, "bad_frames"), 0.0);  // no depth is a valid frame, not a bad one
  EXPECT_LE(count(run, "tracked") + count(run, "posed_by_depth") + count(run, "relocalized") +
                count(run, "lost"),
            count(run, "frames_read"));
  const std::size_t poses = test::countDataLines((out / "trajectory.txt").string());
  EXPECT_GE(poses, 20u);
  EXPECT_LE(poses, kFrames);
}

TEST(FaultInjection, LongTrackingLossRelocalizesOrReportsLost) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  constexpr std::size_t kFrames = 50;
  const fs::path seq = test::makeTeddySubset("fault_blackout", kFrames);
  const auto rgb_files = listedFiles(seq / "rgb.txt");
  const auto depth_files = listedFiles(seq / "depth.txt");
  ASSERT_GE(rgb_files.size(), 40u);
  ASSERT_GE(depth_files.size(), 40u);
  // 20 frames of black images without depth: nothing to track.
  const cv::Mat black = cv::Mat::zeros(480, 640, CV_8UC3);
  const cv::Mat zeros = cv::Mat::zeros(480, 640, CV_16UC1);
  for (std::size_t i = 15; i < 35; ++i) {
    overwriteImage(seq, rgb_files[i], black);
    overwriteImage(seq, depth_files[i], zeros);
  }
  const fs::path out = test::freshTempDir("fault_blackout_out");
  const auto r = runFast(seq, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json run = readJsonFile((out / "run.json").string());
  EXPECT_EQ(stringMember(run, "status").value_or(""), "complete");
  EXPECT_EQ(count(run, "frames_read"), static_cast<double>(kFrames));
  EXPECT_EQ(count(run, "bad_frames"), 0.0);
  EXPECT_GE(count(run, "lost"), 1.0) << "black frames cannot be tracked";
  EXPECT_LE(count(run, "tracked") + count(run, "posed_by_depth") + count(run, "relocalized") +
                count(run, "lost"),
            count(run, "frames_read"));
  // The frames before the blackout keep their poses.
  EXPECT_GE(test::countDataLines((out / "trajectory.txt").string()), 15u);
  EXPECT_NE(test::readFile((out / "keyframes.txt").string()), "");
}

}  // namespace
}  // namespace dynamap
