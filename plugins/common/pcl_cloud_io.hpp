#pragma once

// PCL export shared by the point-cloud backends (header-only, compiled into each plugin).

#include <filesystem>
#include <string>

#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "dynamap/mapping/in_two.hpp"
#include "dynamap/mapping/map_backend.hpp"
#include "dynamap/mapping/ply_io.hpp"

namespace dynamap::plugin {

/// Writes <dir>/cloud.ply and <dir>/cloud.pcd (binary), each atomically, one on each of two
/// threads (inTwo).
inline void saveCloudPlyPcd(const pcl::PointCloud<pcl::PointXYZRGB>& cloud,
                            const std::string& dir) {
  std::filesystem::create_directories(dir);
  const std::string base = (std::filesystem::path(dir) / "cloud").string();
  inTwo([&](int file) {
    if (file == 0) {
      writeAtomically(base + ".pcd", [&](const std::string& tmp) {
        if (pcl::io::savePCDFileBinary(tmp, cloud) != 0) {
          throw MappingError(tmp + ": PCD write failed");
        }
      });
      return;
    }
    // The project's PLY writer: 3-4 x faster than PCL's for a million points, same format.
    PlyData ply;
    ply.vertices.reserve(cloud.size());
    ply.colors.reserve(cloud.size());
    for (const auto& p : cloud) {
      ply.vertices.emplace_back(p.x, p.y, p.z);
      ply.colors.push_back({p.r, p.g, p.b});
    }
    writeAtomically(base + ".ply", [&](const std::string& tmp) { writePly(tmp, ply); });
  });
}

/// <dir>/cloud.ply as saveCloudPlyPcd() wrote it (world points; light grey where the file has
/// no colours). Throws MappingError naming the file: missing, not a PLY, truncated, a point
/// that is not finite.
inline PlyData loadCloudPly(const std::string& dir) {
  const std::string path = (std::filesystem::path(dir) / "cloud.ply").string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw MappingError(path + ": no such file");
  PlyData ply = readPly(path);
  for (std::size_t i = 0; i < ply.vertices.size(); ++i) {
    if (!ply.vertices[i].allFinite()) {
      throw MappingError(path + ": vertex " + std::to_string(i) + ": x/y/z is not finite");
    }
  }
  ply.colors.resize(ply.vertices.size(), {200, 200, 200});
  return ply;
}

inline pcl::PointXYZRGB makePoint(const Eigen::Vector3f& p, const std::array<std::uint8_t, 3>& c) {
  pcl::PointXYZRGB q;
  q.x = p.x();
  q.y = p.y();
  q.z = p.z();
  q.r = c[0];
  q.g = c[1];
  q.b = c[2];
  return q;
}

}  // namespace dynamap::plugin
