#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "dynamap/mapping/ply_io.hpp"
#include "map_export.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {
namespace fs = std::filesystem;

PlyData grid(int n, bool with_faces) {
  PlyData map;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      map.vertices.emplace_back(0.1f * i, 0.1f * j, 0.25f);
      map.colors.push_back({static_cast<std::uint8_t>(10 * i), static_cast<std::uint8_t>(j), 7});
    }
  }
  if (with_faces) {
    for (int i = 0; i + 1 < n; ++i) {
      for (int j = 0; j + 1 < n; ++j) {
        const auto a = static_cast<std::uint32_t>(i * n + j);
        map.triangles.push_back({a, a + 1, a + static_cast<std::uint32_t>(n)});
      }
    }
  }
  return map;
}

std::vector<std::string> lines(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

TEST(MapExport, CloudFolderToPcdXyzPlyKeepsEveryPoint) {
  const fs::path dir = test::freshTempDir("map_export_cloud");
  fs::create_directories(dir / "map");
  const PlyData map = grid(12, false);
  writePly((dir / "map" / "cloud.ply").string(), map);

  const MapExportResult pcd = exportMap((dir / "map").string(), (dir / "out.pcd").string());
  EXPECT_EQ(pcd.points, 144u);
  const auto pcd_lines = lines(dir / "out.pcd");
  std::size_t header = 0;
  while (header < pcd_lines.size() && pcd_lines[header] != "DATA ascii") ++header;
  ASSERT_LT(header, pcd_lines.size());
  EXPECT_EQ(pcd_lines.size() - header - 1, 144u);
  EXPECT_NE(std::find(pcd_lines.begin(), pcd_lines.end(), "POINTS 144"), pcd_lines.end());
  EXPECT_NE(std::find(pcd_lines.begin(), pcd_lines.end(), "FIELDS x y z rgb"), pcd_lines.end());
  // Last point (1.1, 1.1, 0.25), colour (110, 11, 7) packed as 0x006E0B07.
  EXPECT_EQ(pcd_lines.back(), "1.100000 1.100000 0.250000 " + std::to_string(0x6E0B07));

  exportMap((dir / "map").string(), (dir / "out.xyz").string());
  const auto xyz = lines(dir / "out.xyz");
  ASSERT_EQ(xyz.size(), 144u);
  EXPECT_EQ(xyz[1], "0.000000 0.100000 0.250000 0 1 7");

  exportMap((dir / "map" / "cloud.ply").string(), (dir / "copy.PLY").string());
  const PlyData back = readPly((dir / "copy.PLY").string());
  ASSERT_EQ(back.vertices.size(), map.vertices.size());
  EXPECT_TRUE(back.vertices[77].isApprox(map.vertices[77]));
  EXPECT_EQ(back.colors[77], map.colors[77]);
}

TEST(MapExport, MeshToObjKeepsFacesAndPcdDropsThem) {
  const fs::path dir = test::freshTempDir("map_export_mesh");
  const PlyData mesh = grid(5, true);
  writePly((dir / "mesh.ply").string(), mesh);
  const MapExportResult obj = exportMap(dir.string(), (dir / "mesh.obj").string());
  EXPECT_EQ(obj.points, 25u);
  EXPECT_EQ(obj.triangles, 16u);
  std::size_t v = 0, f = 0;
  for (const std::string& line : lines(dir / "mesh.obj")) {
    v += line.rfind("v ", 0) == 0;
    f += line.rfind("f ", 0) == 0;
  }
  EXPECT_EQ(v, 25u);
  EXPECT_EQ(f, 16u);
  const MapExportResult pcd = exportMap(dir.string(), (dir / "mesh.pcd").string());
  EXPECT_TRUE(pcd.dropped_faces);
  EXPECT_EQ(pcd.points, 25u);
}

TEST(MapExport, ErrorsNameTheFile) {
  const fs::path dir = test::freshTempDir("map_export_errors");
  auto message = [](const std::string& map, const std::string& to) {
    try {
      exportMap(map, to);
    } catch (const MapExportError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string missing = (dir / "nope").string();
  EXPECT_NE(message(missing, (dir / "a.pcd").string()).find(missing), std::string::npos);
  EXPECT_NE(message(dir.string(), (dir / "a.pcd").string()).find("neither cloud.ply nor mesh.ply"),
            std::string::npos);
  writePly((dir / "cloud.ply").string(), grid(2, false));
  const std::string bad_ext = (dir / "a.las").string();
  EXPECT_NE(message(dir.string(), bad_ext).find(bad_ext), std::string::npos);
  const std::string unwritable = (dir / "no_such_dir" / "x" / "a.xyz").string();
  fs::create_directories(dir / "no_such_dir");
  fs::permissions(dir / "no_such_dir", fs::perms::owner_read | fs::perms::owner_exec);
  const std::string m = message(dir.string(), unwritable);
  fs::permissions(dir / "no_such_dir", fs::perms::owner_all);
  if (::geteuid() != 0) {  // root may write anyway
    EXPECT_NE(m.find(unwritable), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace dynamap
