// Clouds written piece by piece (plugins/common/pcl_cloud_io.hpp, PlyWriter): the same files as
// PCL's PCD writer and writePly() make from the whole cloud, and a wrong count is an error.
#ifdef DYNAMAP_TEST_WITH_PCL
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "dynamap/mapping/ply_writer.hpp"
#include "pcl_cloud_io.hpp"

namespace dynamap {
namespace cloud_writers_test {
namespace fs = std::filesystem;

std::string fileBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

fs::path freshDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("dynamap_cloud_writers_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// 1000 points with varied coordinates and colours, as PlyData.
PlyData someCloud() {
  PlyData c;
  for (int i = 0; i < 1000; ++i) {
    c.vertices.emplace_back(0.01f * i, -0.5f + 0.003f * (i % 97), 1.0f + 1e-4f * i * i);
    c.colors.push_back({static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(3 * i),
                        static_cast<std::uint8_t>(255 - i % 256)});
  }
  return c;
}

/// `cloud` handed over in pieces of 1, 0, 300 and the rest points.
plugin::CloudPieces piecesOf(const PlyData& cloud) {
  return [&cloud](const std::function<void(const plugin::CloudPiece&)>& emit) {
    std::size_t begin = 0;
    for (const std::size_t n :
         {std::size_t{1}, std::size_t{0}, std::size_t{300}, cloud.vertices.size() - 301}) {
      emit({cloud.vertices.data() + begin, cloud.colors.data() + begin, n});
      begin += n;
    }
  };
}

TEST(CloudWriters, PiecesGiveThePcdAndPlyOfTheWholeCloud) {
  const PlyData cloud = someCloud();
  const fs::path whole = freshDir("whole"), pieces = freshDir("pieces");
  pcl::PointCloud<pcl::PointXYZRGB> pcl_cloud;
  for (std::size_t i = 0; i < cloud.vertices.size(); ++i) {
    pcl_cloud.push_back(plugin::makePoint(cloud.vertices[i], cloud.colors[i]));
  }
  ASSERT_EQ(pcl::io::savePCDFileBinary((whole / "cloud.pcd").string(), pcl_cloud), 0);
  writePly((whole / "cloud.ply").string(), cloud);

  plugin::saveCloudPlyPcd(cloud.vertices.size(), piecesOf(cloud), pieces.string());
  EXPECT_EQ(fileBytes(pieces / "cloud.pcd"), fileBytes(whole / "cloud.pcd"));
  EXPECT_EQ(fileBytes(pieces / "cloud.ply"), fileBytes(whole / "cloud.ply"));

  pcl::PointCloud<pcl::PointXYZRGB> back;
  ASSERT_EQ(pcl::io::loadPCDFile((pieces / "cloud.pcd").string(), back), 0);
  ASSERT_EQ(back.size(), cloud.vertices.size());
  EXPECT_EQ(back[999].x, cloud.vertices[999].x());
  EXPECT_EQ(back[999].b, cloud.colors[999][2]);
}

TEST(CloudWriters, PclCloudOverloadWritesTheSameFiles) {
  const PlyData cloud = someCloud();
  pcl::PointCloud<pcl::PointXYZRGB> pcl_cloud;
  for (std::size_t i = 0; i < cloud.vertices.size(); ++i) {
    pcl_cloud.push_back(plugin::makePoint(cloud.vertices[i], cloud.colors[i]));
  }
  const fs::path a = freshDir("pcl"), b = freshDir("pieces2");
  plugin::saveCloudPlyPcd(pcl_cloud, a.string());
  plugin::saveCloudPlyPcd(cloud.vertices.size(), piecesOf(cloud), b.string());
  EXPECT_EQ(fileBytes(a / "cloud.pcd"), fileBytes(b / "cloud.pcd"));
  EXPECT_EQ(fileBytes(a / "cloud.ply"), fileBytes(b / "cloud.ply"));
}

TEST(CloudWriters, FewerPointsThanAnnouncedIsAnErrorAndLeavesNoFile) {
  const PlyData cloud = someCloud();
  const fs::path dir = freshDir("short");
  EXPECT_THROW(plugin::saveCloudPlyPcd(cloud.vertices.size() + 1, piecesOf(cloud), dir.string()),
               MappingError);
  EXPECT_FALSE(fs::exists(dir / "cloud.pcd"));
  EXPECT_FALSE(fs::exists(dir / "cloud.ply"));
  PlyWriter ply((dir / "mesh.ply").string(), 2, false, 1);
  ply.addVertices(cloud.vertices.data(), nullptr, 2);
  EXPECT_THROW(ply.close(), MappingError);  // the face never came
}

}  // namespace cloud_writers_test
}  // namespace dynamap
#endif  // DYNAMAP_TEST_WITH_PCL
