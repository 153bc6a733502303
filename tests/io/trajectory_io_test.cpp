#include "trajectory_io.hpp"

#include <fstream>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "image_io.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

namespace fs = std::filesystem;

void writeText(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

std::string errorOf(const std::string& path) {
  try {
    readTrajectory(path);
  } catch (const DatasetError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(TrajectoryIo, WriteReadRoundTrip) {
  const fs::path dir = test::freshTempDir("traj_roundtrip");
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::vector<TimedPose> poses;
  for (int k = 0; k < 200; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().matrix();
    T.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng));
    poses.push_back({1341841873.273798 + 0.033 * k, T});
  }
  const std::string path = (dir / "traj.txt").string();
  writeTrajectory(path, poses);
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  const std::vector<TimedPose> back = readTrajectory(path);
  ASSERT_EQ(back.size(), poses.size());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    EXPECT_NEAR(back[k].timestamp_s, poses[k].timestamp_s, 1e-6);
    EXPECT_LT((back[k].T_W_C.translation() - poses[k].T_W_C.translation()).norm(), 1e-6);
    EXPECT_LT((back[k].T_W_C.linear() - poses[k].T_W_C.linear()).norm(), 1e-6);
  }
  // Overwriting an existing file works (rename onto it).
  writeTrajectory(path, {poses.front()});
  EXPECT_EQ(readTrajectory(path).size(), 1u);
}

TEST(TrajectoryIo, AcceptsNoHeaderCommasTabsAndComments) {
  const fs::path dir = test::freshTempDir("traj_format");
  const fs::path path = dir / "t.txt";
  writeText(path,
            "2.0,1,2,3,0,0,0,1\n# comment\n\n1.0\t0 0 0\t0 0 0 2\r\n"
            "3.0 , 0 , 0 , 0 , 0 , 0 , 1 , 0\n");
  const auto poses = readTrajectory(path.string());
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_EQ(poses[0].timestamp_s, 1.0);                    // sorted by time
  EXPECT_TRUE(poses[0].T_W_C.linear().isIdentity(1e-12));  // (0,0,0,2) normalised
  EXPECT_EQ(poses[1].T_W_C.translation(), Eigen::Vector3d(1, 2, 3));
  // 180 degrees about z.
  EXPECT_NEAR(poses[2].T_W_C.linear()(0, 0), -1.0, 1e-12);
}

TEST(TrajectoryIo, DuplicateTimestampLaterLineWinsAndZeroQuaternionIsIdentity) {
  const fs::path dir = test::freshTempDir("traj_dup");
  const fs::path path = dir / "t.txt";
  writeText(path, "1.0 1 1 1 0 0 0 1\n1.0 5 5 5 0 0 0 0\n");
  const auto poses = readTrajectory(path.string());
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0].T_W_C.translation(), Eigen::Vector3d(5, 5, 5));
  EXPECT_TRUE(poses[0].T_W_C.linear().isIdentity(0.0));
}

TEST(TrajectoryIo, ErrorsNameFileAndLine) {
  const fs::path dir = test::freshTempDir("traj_errors");
  const std::string path = (dir / "t.txt").string();
  EXPECT_NE(errorOf(path).find("cannot open " + path), std::string::npos) << errorOf(path);
  writeText(path, "# h\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n");
  EXPECT_NE(errorOf(path).find(path + ":3: expected 8 fields"), std::string::npos) << errorOf(path);
  EXPECT_NE(errorOf(path).find("found 7"), std::string::npos) << errorOf(path);
  writeText(path, "1.0 0 0 0 0 0 0 1\n2.0 0 abc 0 0 0 0 1\n");
  EXPECT_NE(errorOf(path).find(path + ":2: ty 'abc' is not a finite number"), std::string::npos)
      << errorOf(path);
  writeText(path, "1.0 0 0 nan 0 0 0 1\n");
  EXPECT_NE(errorOf(path).find(path + ":1: tz 'nan'"), std::string::npos) << errorOf(path);
}

TEST(ImageIo, WriteTextFileAtomicReplacesContent) {
  const fs::path dir = test::freshTempDir("atomic_text");
  const std::string path = (dir / "a.json").string();
  writeTextFileAtomic(path, "first");
  writeTextFileAtomic(path, "second");
  std::ifstream in(path);
  std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(content, "second");
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  EXPECT_THROW(writeTextFileAtomic((dir / "no_dir" / "x.txt").string(), "x"), std::runtime_error);
}

}  // namespace
}  // namespace dynamap
