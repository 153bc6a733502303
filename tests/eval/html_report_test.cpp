#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "dynamap/mapping/ply_io.hpp"
#include "html_report.hpp"
#include "json_reader.hpp"
#include "test_paths.hpp"
#include "trajectory_io.hpp"

namespace dynamap {
namespace {
namespace fs = std::filesystem;

std::string readText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeText(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

/// A finished run folder: run.json, metrics.json, timings.json, trajectory.txt (ground truth
/// plus ~1 cm noise), map/cloud.ply; returns the ground-truth path.
std::string makeRunFolder(const fs::path& dir) {
  writeText(dir / "run.json",
            R"({"status": "complete", "counts": {"frames_read": 60, "tracked": 58, "lost": 2,)"
            R"( "keyframes": 12}, "backend": "points"})");
  writeText(dir / "metrics.json",
            R"({"ate": {"pairs": 60, "rmse_m": 0.0123, "max_m": 0.03},)"
            R"( "rpe": {"pairs": 50, "trans_rmse_m": 0.02, "rot_rmse_deg": 0.5},)"
            R"( "map": {"file": "cloud.ply", "fscore": 0.8126, "ghost_ratio": 0.004}})");
  writeText(dir / "timings.json",
            R"({"frames": 60, "frames_per_s": 24.5, "peak_memory_mib": 512.0,)"
            R"( "stages": {"tracking": {"count": 60, "median_ms": 11.5, "p95_ms": 19.26,)"
            R"( "mean_ms": 12.0, "max_ms": 25.0}, "mapping": {"count": 12, "median_ms": 40.0,)"
            R"( "p95_ms": 80.0, "mean_ms": 45.0, "max_ms": 90.0}}})");
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<TimedPose> gt, est;
  for (int i = 0; i < 60; ++i) {
    TimedPose pose{1000.0 + i / 30.0, Eigen::Isometry3d::Identity()};
    pose.T_W_C.translation() = Eigen::Vector3d(std::cos(i * 0.05), std::sin(i * 0.05), 0.0);
    gt.push_back(pose);
    pose.T_W_C.translation() += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    est.push_back(pose);
  }
  writeTrajectory((dir / "trajectory.txt").string(), est);
  writeTrajectory((dir / "gt.txt").string(), gt);
  PlyData cloud;
  for (int i = 0; i < 2000; ++i) {
    cloud.vertices.emplace_back(std::cos(i * 0.01f) * 2.0f, std::sin(i * 0.01f) * 2.0f,
                                0.001f * (i % 100));
    cloud.colors.push_back({static_cast<std::uint8_t>(i % 256), 100, 50});
  }
  fs::create_directories(dir / "map");
  writePly((dir / "map" / "cloud.ply").string(), cloud);
  return (dir / "gt.txt").string();
}

TEST(HtmlReport, FullRunFolderHasAllSectionsAndImages) {
  const fs::path dir = test::freshTempDir("html_report_full");
  const std::string gt = makeRunFolder(dir);
  const std::string notes = writeHtmlReport(dir.string(), "synthetic_seq", gt);
  EXPECT_EQ(notes, "");
  const std::string html = readText(dir / "report.html");
  for (const char* needle :
       {"<!DOCTYPE html>", "synthetic_seq", "id=\"run\"", "id=\"metrics\"", "id=\"trajectory\"",
        "id=\"map\"", "id=\"timings\"", "status complete", "1.23 cm",  // ATE rmse in cm
        "0.813", "19.3 ms",                                            // F-score, tracking p95
        "24.5", "512 MiB", "tracking", "mapping", "frames read", "map/cloud.ply"}) {
    EXPECT_NE(html.find(needle), std::string::npos) << "missing: " << needle;
  }
  EXPECT_EQ(html.find("<script"), std::string::npos);
  for (const char* image : {"trajectory.png", "ate_over_time.png", "map_preview_top.png",
                            "map_preview_oblique_1.png", "map_preview_oblique_2.png"}) {
    EXPECT_NE(html.find(std::string("src=\"") + image + "\""), std::string::npos) << image;
    const cv::Mat png = cv::imread((dir / image).string());
    EXPECT_FALSE(png.empty()) << image;
  }
}

TEST(HtmlReport, MissingInputsAreNotedNotFatal) {
  const fs::path dir = test::freshTempDir("html_report_empty");
  writeText(dir / "run.json", R"({"status": "failed", "error": "x < y", "counts": {}})");
  const std::string notes = writeHtmlReport(dir.string(), "empty", "");
  EXPECT_NE(notes.find("metrics.json not found"), std::string::npos);
  EXPECT_NE(notes.find("no map"), std::string::npos);
  const std::string html = readText(dir / "report.html");
  EXPECT_NE(html.find("status failed"), std::string::npos);
  EXPECT_NE(html.find("x &lt; y"), std::string::npos);  // escaped
  EXPECT_EQ(html.find("<img"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "ate_over_time.png"));
}

TEST(HtmlReport, BrokenJsonIsNotedWithItsFileName) {
  const fs::path dir = test::freshTempDir("html_report_broken");
  writeText(dir / "metrics.json", "{\"ate\": {\"rmse_m\": 0.1,}");
  const std::string notes = writeHtmlReport(dir.string(), "broken", "");
  EXPECT_NE(notes.find("metrics.json: invalid JSON at byte"), std::string::npos) << notes;
  EXPECT_TRUE(fs::exists(dir / "report.html"));
}

TEST(JsonReader, ParsesNestedValuesAndEscapes) {
  const JsonValue v =
      parseJson(R"({"a": 1.5e2, "b": [true, false, null], "c": {"d": "x\"y\u00e9\n"}, "e": -3})");
  EXPECT_DOUBLE_EQ(*v.number("a"), 150.0);
  ASSERT_EQ(v.find("b")->items().size(), 3u);
  EXPECT_TRUE(v.find("b")->items()[0].asBool());
  EXPECT_EQ(v.find("b")->items()[2].type(), JsonValue::Type::kNull);
  EXPECT_EQ(*v.find("c")->string("d"), "x\"y\xc3\xa9\n");
  EXPECT_DOUBLE_EQ(*v.number("e"), -3.0);
  EXPECT_FALSE(v.number("missing").has_value());
  EXPECT_FALSE(v.number("c").has_value());
  EXPECT_THROW(parseJson("{\"a\": }", "t"), JsonParseError);
  EXPECT_THROW(parseJson("[1, 2", "t"), JsonParseError);
  EXPECT_THROW(parseJson("{} x", "t"), JsonParseError);
}

}  // namespace
}  // namespace dynamap
