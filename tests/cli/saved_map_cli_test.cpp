// `dynamap run --save-map / --load-map` and `dynamap evaluate --save-alignment / --alignment`:
// a second run starts in the first run's map and is judged in its frame; a bad map is one error
// line before any frame; a save that fails keeps every output of the run.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "cli_test_util.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

namespace fs = std::filesystem;
using test::runDynamap;

std::vector<std::string> fastRun(const std::string& seq, const fs::path& out,
                                 std::vector<std::string> extra) {
  std::vector<std::string> args = {
      "run",   "--sequence",       seq,      "--out", out.string(),
      "--set", "dynamic.mode=off", "--quiet"};  // default backend pcl_voxel
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

TEST(RunCommand, SecondRunStartsInTheSavedMapAndIsJudgedInItsFrame) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const std::string seq = test::makeTeddySubset("cli_saved_map40", 40);
  const fs::path dir = test::freshTempDir("cli_saved_map");
  const auto first = runDynamap(fastRun(seq, dir / "one", {"--save-map", (dir / "m").string()}));
  ASSERT_EQ(first.exit_code, 0) << first.err;
  ASSERT_TRUE(fs::exists(dir / "m" / "map.sqlite"));
  const auto align = runDynamap({"evaluate", "--gt", seq + "/groundtruth.txt", "--est",
                                 (dir / "one" / "trajectory.txt").string(), "--save-alignment",
                                 (dir / "align.txt").string()});
  ASSERT_EQ(align.exit_code, 0) << align.err;
  const auto second = runDynamap(fastRun(seq, dir / "two", {"--load-map", (dir / "m").string()}));
  ASSERT_EQ(second.exit_code, 0) << second.err;
  EXPECT_NE(test::readFile((dir / "two" / "run.json").string()).find("\"loaded_keyframes\""),
            std::string::npos);
  EXPECT_GE(test::countDataLines((dir / "two" / "trajectory.txt").string()), 38u);  // <= 2 lost
  const auto judged = runDynamap({"evaluate", "--gt", seq + "/groundtruth.txt", "--est",
                                  (dir / "two" / "trajectory.txt").string(), "--alignment",
                                  (dir / "align.txt").string(), "--json"});
  ASSERT_EQ(judged.exit_code, 0) << judged.err;
  EXPECT_NE(judged.out.find("\"alignment\":\"given\""), std::string::npos) << judged.out;
  const auto rmse_at = judged.out.find("\"rmse_m\":");
  ASSERT_NE(rmse_at, std::string::npos) << judged.out;
  EXPECT_LT(std::stod(judged.out.substr(rmse_at + 9)), 0.02) << judged.out;  // issue 47's 2 cm
}

TEST(RunCommand, BadSavedMapIsOneErrorLineBeforeAnyFrame) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const std::string seq = test::makeTeddySubset("cli_teddy5_bad_map", 5);
  const fs::path dir = test::freshTempDir("cli_saved_map_bad");
  const auto r = runDynamap(fastRun(seq, dir / "out", {"--load-map", (dir / "none").string()}));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find((dir / "none" / "map.sqlite").string() + ": no such map file"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "trajectory.txt"));
}

TEST(RunCommand, FailedSaveKeepsEveryOutputOfTheRun) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const std::string seq = test::makeTeddySubset("cli_teddy20_failed_save", 20);
  const fs::path dir = test::freshTempDir("cli_saved_map_fail");
  std::ofstream(dir / "a_file") << "not a folder";
  const auto r =
      runDynamap(fastRun(seq, dir / "out", {"--save-map", (dir / "a_file" / "m").string()}));
  EXPECT_EQ(r.exit_code, 1);
  const std::string run_json = test::readFile((dir / "out" / "run.json").string());
  EXPECT_NE(run_json.find("\"failed\""), std::string::npos) << run_json;
  EXPECT_NE(run_json.find((dir / "a_file" / "m").string()), std::string::npos) << run_json;
  EXPECT_EQ(test::countDataLines((dir / "out" / "trajectory.txt").string()), 20u);
  EXPECT_TRUE(fs::exists(dir / "out" / "map" / "cloud.ply"));
}

}  // namespace
}  // namespace dynamap
