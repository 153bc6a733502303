#include "tum_dataset.hpp"

#include <cmath>
#include <fstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "frame_prefetch.hpp"
#include "test_paths.hpp"

namespace dynamap::tum_dataset_test {
namespace {

namespace fs = std::filesystem;

void writeText(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

/// Expects `fn` to throw DatasetError whose message contains every string in `parts`.
template <typename Fn>
void expectDatasetError(Fn fn, std::initializer_list<std::string> parts) {
  try {
    fn();
    FAIL() << "expected DatasetError";
  } catch (const DatasetError& e) {
    for (const std::string& part : parts) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
          << "'" << part << "' not in: " << e.what();
    }
  }
}

/// A small synthetic sequence: 3 colour (64x48) and 3 depth images, headers as TUM writes.
fs::path makeSequence(const std::string& name) {
  const fs::path dir = test::freshTempDir(name);
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  std::string rgb_txt = "# color images\n# file: 'x.bag'\n# timestamp filename\n";
  std::string depth_txt = "# depth maps\n# file: 'x.bag'\n# timestamp filename\n";
  for (int k = 0; k < 3; ++k) {
    const std::string t_rgb = std::to_string(10.0 + 0.1 * k);
    const std::string t_depth = std::to_string(10.0 + 0.1 * k + 0.004);
    cv::Mat bgr(48, 64, CV_8UC3, cv::Scalar(10 * k, 20, 30));
    cv::Mat depth(48, 64, CV_16UC1, cv::Scalar(5000 + 1000 * k));
    depth.at<std::uint16_t>(0, 0) = 0;
    cv::imwrite((dir / "rgb" / (t_rgb + ".png")).string(), bgr);
    cv::imwrite((dir / "depth" / (t_depth + ".png")).string(), depth);
    rgb_txt += t_rgb + " rgb/" + t_rgb + ".png\n";
    depth_txt += t_depth + " depth/" + t_depth + ".png\n";
  }
  writeText(dir / "rgb.txt", rgb_txt);
  writeText(dir / "depth.txt", depth_txt);
  return dir;
}

DatasetOptions smallCameraOptions() {
  DatasetOptions options;
  options.camera.width = 64;
  options.camera.height = 48;
  return options;
}

TEST(Association, GreedyByDifferenceOneToOne) {
  // Candidates: (0.015,0.010) diff .005, (0.000,0.010) diff .010, (0.015,0.030) diff .015.
  // Greedy takes the first; the others reuse a stamp -> exactly one match.
  const auto m = associateTimestamps({0.0, 0.015}, {0.010, 0.030}, 0.02);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].first, 1u);
  EXPECT_EQ(m[0].second, 0u);
}

TEST(Association, WindowIsStrictAndResultSortedByFirst) {
  EXPECT_TRUE(associateTimestamps({1.0}, {1.03}, 0.02).empty());
  EXPECT_EQ(associateTimestamps({1.0}, {1.03}, 0.05).size(), 1u);
  // Unsorted input; output sorted by the first stamp.
  const auto m = associateTimestamps({3.0, 1.0, 2.0}, {2.001, 0.999, 3.002}, 0.02);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0], std::make_pair(std::size_t{1}, std::size_t{1}));
  EXPECT_EQ(m[1], std::make_pair(std::size_t{2}, std::size_t{0}));
  EXPECT_EQ(m[2], std::make_pair(std::size_t{0}, std::size_t{2}));
}

TEST(TumSequence, OpensAssociatesAndLoadsSyntheticSequence) {
  const fs::path dir = makeSequence("seq_ok");
  const TumSequence seq = TumSequence::open(dir.string(), smallCameraOptions());
  ASSERT_EQ(seq.size(), 3u);
  EXPECT_NEAR(seq.entries()[1].rgb_timestamp_s, 10.1, 1e-9);
  EXPECT_NEAR(seq.entries()[1].depth_timestamp_s, 10.104, 1e-9);
  EXPECT_TRUE(fs::path(seq.entries()[0].rgb_path).is_absolute());
  EXPECT_FALSE(seq.groundTruthPath().has_value());
  const FrameLoad f = seq.load(2);
  ASSERT_TRUE(f.ok) << f.error;
  EXPECT_EQ(f.frame.index, 2u);
  EXPECT_EQ(f.frame.bgr.type(), CV_8UC3);
  ASSERT_EQ(f.frame.depth_m.type(), CV_32FC1);
  EXPECT_FLOAT_EQ(f.frame.depth_m.at<float>(5, 5), 7000.0f / 5000.0f);
  EXPECT_EQ(f.frame.depth_m.at<float>(0, 0), 0.0f);  // 0 = no reading
  EXPECT_EQ(f.frame.bgr.at<cv::Vec3b>(3, 3), cv::Vec3b(20, 20, 30));
  writeText(dir / "groundtruth.txt", "1 0 0 0 0 0 0 1\n");
  EXPECT_EQ(seq.groundTruthPath().value(), (dir / "groundtruth.txt").string());
}

TEST(TumSequence, NoHeaderCommasTabsAndMaxFrames) {
  const fs::path dir = makeSequence("seq_format");
  writeText(dir / "rgb.txt",
            "10.000000,rgb/10.000000.png\n10.100000\trgb/10.100000.png\n"
            "10.200000 , rgb/10.200000.png\n");
  writeText(dir / "depth.txt",
            "10.004000 depth/10.004000.png\n\n10.104000 depth/10.104000.png\r\n"
            "10.204000\t\tdepth/10.204000.png\n");
  EXPECT_EQ(TumSequence::open(dir.string(), smallCameraOptions()).size(), 3u);
  DatasetOptions options = smallCameraOptions();
  options.max_frames = 2;
  EXPECT_EQ(TumSequence::open(dir.string(), options).size(), 2u);
  options.max_time_diff_s = 0.003;  // depth lags 4 ms -> nothing associates
  options.keep_unassociated_rgb = false;
  EXPECT_EQ(TumSequence::open(dir.string(), options).size(), 0u);
  // Kept colour-only frames load with an all-zero depth image.
  options.keep_unassociated_rgb = true;
  const TumSequence kept = TumSequence::open(dir.string(), options);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_TRUE(kept.entries()[0].depth_path.empty());
}

TEST(TumSequence, MissingListFilesAreNamed) {
  const fs::path dir = makeSequence("seq_missing");
  fs::remove(dir / "depth.txt");
  expectDatasetError([&] { TumSequence::open(dir.string(), smallCameraOptions()); },
                     {"depth.txt", dir.string()});
  fs::remove(dir / "rgb.txt");
  expectDatasetError([&] { TumSequence::open(dir.string(), smallCameraOptions()); }, {"rgb.txt"});
  expectDatasetError([&] { TumSequence::open((dir / "nope").string(), smallCameraOptions()); },
                     {"nope", "does not exist"});
}

TEST(TumSequence, MalformedLinesNameFileAndLine) {
  const fs::path dir = makeSequence("seq_malformed");
  writeText(dir / "rgb.txt", "# header\n10.0 rgb/a.png\n10.1 rgb/b.png extra\n");
  expectDatasetError([&] { TumSequence::open(dir.string(), smallCameraOptions()); },
                     {(dir / "rgb.txt").string() + ":3:", "expected 2 fields"});
  writeText(dir / "rgb.txt", "10.0 rgb/a.png\n");
  writeText(dir / "depth.txt", "# a\n# b\n# c\n10.0 depth/a.png\nten depth/b.png\n");
  expectDatasetError([&] { TumSequence::open(dir.string(), smallCameraOptions()); },
                     {(dir / "depth.txt").string() + ":5:", "'ten'", "not a finite number"});
}

TEST(TumSequence, OutOfOrderAndRepeatedTimestampsAreErrors) {
  const fs::path dir = makeSequence("seq_order");
  writeText(dir / "rgb.txt", "10.0 rgb/a.png\n10.2 rgb/b.png\n10.1 rgb/c.png\n");
  expectDatasetError([&] { TumSequence::open(dir.string(), smallCameraOptions()); },
                     {(dir / "rgb.txt").string() + ":3:", "out of order", "line 2"});
  writeText(dir / "rgb.txt", "10.0 rgb/a.png\n");
  writeText(dir / "depth.txt", "10.0 depth/a.png\n10.0 depth/b.png\n");
  expectDatasetError([&] { TumSequence::open(dir.string(), smallCameraOptions()); },
                     {(dir / "depth.txt").string() + ":2:", "repeats"});
}

TEST(TumSequence, BadFramesAreValuesNotExceptions) {
  const fs::path dir = makeSequence("seq_bad");
  const TumSequence seq = TumSequence::open(dir.string(), smallCameraOptions());
  // Wrong-size depth.
  cv::imwrite(seq.entries()[0].depth_path, cv::Mat(24, 32, CV_16UC1, cv::Scalar(1000)));
  FrameLoad f = seq.load(0);
  EXPECT_FALSE(f.ok);
  EXPECT_NE(f.error.find("32x24"), std::string::npos) << f.error;
  EXPECT_NE(f.error.find("64x48"), std::string::npos) << f.error;
  // Corrupt colour PNG.
  writeText(seq.entries()[1].rgb_path, "\x89PNG\r\n\x1a\n this is not a png");
  f = seq.load(1);
  EXPECT_FALSE(f.ok);
  EXPECT_NE(f.error.find("cannot decode"), std::string::npos) << f.error;
  EXPECT_NE(f.error.find(seq.entries()[1].rgb_path), std::string::npos) << f.error;
  // 8-bit depth.
  cv::imwrite(seq.entries()[2].depth_path, cv::Mat(48, 64, CV_8UC1, cv::Scalar(7)));
  f = seq.load(2);
  EXPECT_FALSE(f.ok);
  EXPECT_NE(f.error.find("not 16-bit single-channel"), std::string::npos) << f.error;
  // Missing image.
  fs::remove(seq.entries()[2].rgb_path);
  f = seq.load(2);
  EXPECT_FALSE(f.ok);
  EXPECT_NE(f.error.find("missing image"), std::string::npos) << f.error;
  EXPECT_FALSE(seq.load(3).ok);  // out of range
}

// The prefetcher hands out exactly what load() gives, in order, after a skipped frame (the
// realtime mode drops stale frames) and for a bad frame (an error value, not an exception).
TEST(FramePrefetcher, GivesWhatLoadGivesInOrderAndAfterASkip) {
  const fs::path dir = makeSequence("seq_prefetch");
  const TumSequence seq = TumSequence::open(dir.string(), smallCameraOptions());
  writeText(seq.entries()[2].rgb_path, "not an image");
  const auto same = [&](const FrameLoad& got, std::size_t i) {
    const FrameLoad want = seq.load(i);
    EXPECT_EQ(got.ok, want.ok) << i;
    EXPECT_EQ(got.error, want.error) << i;
    if (!want.ok) return;
    EXPECT_EQ(got.frame.timestamp_s, want.frame.timestamp_s) << i;
    EXPECT_EQ(cv::norm(got.frame.bgr, want.frame.bgr, cv::NORM_INF), 0.0) << i;
    EXPECT_EQ(cv::norm(got.frame.depth_m, want.frame.depth_m, cv::NORM_INF), 0.0) << i;
  };
  {
    FramePrefetcher frames(seq);
    for (std::size_t i = 0; i < seq.size(); ++i) same(frames.take(i), i);
  }
  FramePrefetcher frames(seq);
  same(frames.take(0), 0);
  same(frames.take(2), 2);  // frame 1 was being read: dropped
  same(frames.take(1), 1);  // back again (not what the pipeline does, but still right)
}

fs::path teddyDir() { return test::sharedData() / "tum" / "rgbd_dataset_freiburg3_teddy"; }

TEST(TumSequenceRealData, TeddyAssociatesLikeAssociatePyWithSaneDepth) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  DatasetOptions options;
  options.camera = cameraPreset("freiburg3");
  options.keep_unassociated_rgb = false;
  const TumSequence seq = TumSequence::open(teddyDir().string(), options);
  // 200 colour and 200 depth images; TUM associate.py (max_difference 0.02) pairs 193 of them
  // (checked with the script's algorithm): 7 colour frames have no free depth within 20 ms,
  // e.g. 1341841877.730182.
  ASSERT_EQ(seq.size(), 193u);
  options.keep_unassociated_rgb = true;  // the other 7 are kept without depth
  const TumSequence all = TumSequence::open(teddyDir().string(), options);
  ASSERT_EQ(all.size(), 200u);
  std::size_t without_depth = 0;
  for (const SequenceEntry& e : all.entries()) without_depth += e.depth_path.empty() ? 1 : 0;
  EXPECT_EQ(without_depth, 7u);
  for (const SequenceEntry& e : seq.entries()) {
    EXPECT_NE(e.rgb_path.find("rgb/"), std::string::npos);
    EXPECT_GT(std::abs(e.rgb_timestamp_s - 1341841877.730182), 1e-4);
  }
  ASSERT_TRUE(seq.groundTruthPath().has_value());
  for (std::size_t i = 1; i < seq.size(); ++i) {
    EXPECT_LT(seq.entries()[i - 1].rgb_timestamp_s, seq.entries()[i].rgb_timestamp_s);
    EXPECT_LT(std::abs(seq.entries()[i].rgb_timestamp_s - seq.entries()[i].depth_timestamp_s),
              0.02);
  }
  // Depth in metres: per-frame medians are plausible indoor distances (the last frames look
  // at the far wall, ~4.4 m); the median over the sequence lies in [0.5, 4] m.
  std::vector<float> frame_medians;
  for (std::size_t i = 0; i < seq.size(); i += 16) {
    const FrameLoad f = seq.load(i);
    ASSERT_TRUE(f.ok) << f.error;
    EXPECT_EQ(f.frame.bgr.size(), cv::Size(640, 480));
    std::vector<float> valid;
    for (auto it = f.frame.depth_m.begin<float>(); it != f.frame.depth_m.end<float>(); ++it) {
      if (*it > 0.0f) valid.push_back(*it);
    }
    ASSERT_GT(valid.size(), 640u * 480u / 2);
    std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
    frame_medians.push_back(valid[valid.size() / 2]);
    EXPECT_GT(frame_medians.back(), 0.3f);
    EXPECT_LT(frame_medians.back(), 6.0f);
  }
  std::nth_element(frame_medians.begin(), frame_medians.begin() + frame_medians.size() / 2,
                   frame_medians.end());
  const float median = frame_medians[frame_medians.size() / 2];
  EXPECT_GT(median, 0.5f);
  EXPECT_LT(median, 4.0f);
}

TEST(TumSequenceRealData, UndistortsFreiburg1ButNotFreiburg3) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  DatasetOptions options;
  options.camera = cameraPreset("freiburg3");
  options.max_frames = 1;
  const FrameLoad plain = TumSequence::open(teddyDir().string(), options).load(0);
  options.camera = cameraPreset("freiburg1");
  const TumSequence fr1 = TumSequence::open(teddyDir().string(), options);
  const FrameLoad undistorted = fr1.load(0);
  ASSERT_TRUE(plain.ok && undistorted.ok);
  const cv::Mat raw = cv::imread(fr1.entries()[0].rgb_path, cv::IMREAD_COLOR);
  EXPECT_EQ(cv::norm(plain.frame.bgr, raw, cv::NORM_INF), 0.0);  // freiburg3: untouched
  const double mean_change = cv::norm(undistorted.frame.bgr, raw, cv::NORM_L1) / raw.total();
  EXPECT_GT(mean_change, 10.0);  // freiburg1 distortion moves pixels visibly
  // Nearest-neighbour depth: every value is still a multiple of 1 / depth_scale.
  int off_grid = 0;
  for (auto it = undistorted.frame.depth_m.begin<float>();
       it != undistorted.frame.depth_m.end<float>(); ++it) {
    const double units = *it * 5000.0;
    off_grid += std::abs(units - std::round(units)) > 1e-2;
  }
  EXPECT_EQ(off_grid, 0);
  EXPECT_GT(cv::norm(undistorted.frame.depth_m, plain.frame.depth_m, cv::NORM_L1), 0.0);
  // Thread-safe const load: two threads, same result.
  FrameLoad a, b;
  std::thread ta([&] { a = fr1.load(0); });
  std::thread tb([&] { b = fr1.load(0); });
  ta.join();
  tb.join();
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_EQ(cv::norm(a.frame.bgr, b.frame.bgr, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.frame.bgr, undistorted.frame.bgr, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace dynamap::tum_dataset_test
