#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "dynamap/mapping/ply_io.hpp"
#include "html_report.hpp"
#include "json_io.hpp"
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

TEST(JsonIo, ReadsFilesAndNamesThemInErrors) {
  const fs::path dir = test::freshTempDir("json_io");
  writeText(dir / "a.json",
            R"({"a": 1.5e2, "b": [true, null], "c": {"d": "x\"y\u00e9"}, "e": "s"})");
  const Json v = readJsonFile((dir / "a.json").string());
  EXPECT_DOUBLE_EQ(*numberMember(v, "a"), 150.0);
  EXPECT_EQ(*stringMember(*findMember(v, "c"), "d"), "x\"y\xc3\xa9");
  EXPECT_FALSE(numberMember(v, "e").has_value());
  EXPECT_FALSE(stringMember(v, "a").has_value());
  EXPECT_EQ(findMember(v, "missing"), nullptr);
  EXPECT_EQ(findMember((*findMember(v, "b"))[0], "x"), nullptr);  // not an object
  std::vector<std::string> keys;
  for (const auto& member : v.items()) keys.push_back(member.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"a", "b", "c", "e"}));  // file order kept
  writeText(dir / "bad.json", "[1, 2");
  try {
    (void)readJsonFile((dir / "bad.json").string());
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json: invalid JSON at byte"), std::string::npos);
  }
  EXPECT_THROW((void)readJsonFile((dir / "none.json").string()), std::runtime_error);
  // Found by json_fuzzer: nlohmann reports a number overflow as out_of_range, not parse_error.
  writeText(dir / "overflow.json", "[1e338, -0, 0.5]");
  try {
    (void)readJsonFile((dir / "overflow.json").string());
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("overflow.json: invalid JSON"), std::string::npos);
  }
}

TEST(JsonIo, DumpNeverThrowsAndWritesNullForNonFiniteNumbers) {
  const Json j = {{"nan", std::numeric_limits<double>::quiet_NaN()},
                  {"inf", std::numeric_limits<double>::infinity()},
                  {"bad_utf8", std::string("a\xff")},
                  {"x", 0.5}};
  EXPECT_EQ(dumpJson(j), "{\"nan\":null,\"inf\":null,\"bad_utf8\":\"a\xef\xbf\xbd\",\"x\":0.5}");
  EXPECT_EQ(dumpJson(Json{{"a", 1}}, 2), "{\n  \"a\": 1\n}");
}

}  // namespace
}  // namespace dynamap
