#pragma once

// PCL export shared by the point-cloud backends (header-only, compiled into each plugin).

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "dynamap/mapping/in_two.hpp"
#include "dynamap/mapping/map_backend.hpp"
#include "dynamap/mapping/ply_io.hpp"
#include "dynamap/mapping/ply_writer.hpp"

namespace dynamap::plugin {

/// A piece of a cloud in the world frame: `n` points and their colours (RGB).
struct CloudPiece {
  const Eigen::Vector3f* points = nullptr;
  const std::array<std::uint8_t, 3>* colors = nullptr;
  std::size_t n = 0;
};
/// Hands every piece of a cloud to `emit`, always in the same order. Called once for each file
/// written, on two threads at once: it must only read shared data.
using CloudPieces = std::function<void(const std::function<void(const CloudPiece&)>& emit)>;

/// <path>: a binary PCD of PointXYZRGB (PCL's header for `points` points, then x y z and the
/// packed rgb of each point: what pcl::io::savePCDFileBinary writes), piece by piece.
inline void writePcdBinary(const std::string& path, std::size_t points, const CloudPieces& pieces) {
  if (points > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw MappingError(path + ": " + std::to_string(points) + " points are more than PCD takes");
  }
  std::ofstream out(path, std::ios::binary);
  if (!out) throw MappingError(path + ": cannot write PCD file");
  out << pcl::PCDWriter::generateHeader(pcl::PointCloud<pcl::PointXYZRGB>(),
                                        static_cast<int>(points))
      << "DATA binary\n";
  std::vector<char> block;
  std::size_t written = 0;
  pieces([&](const CloudPiece& piece) {
    block.resize(piece.n * 16);
    char* record = block.data();
    for (std::size_t i = 0; i < piece.n; ++i, record += 16) {
      const auto& c = piece.colors[i];
      const std::uint32_t rgba =
          0xff000000u | std::uint32_t{c[0]} << 16 | std::uint32_t{c[1]} << 8 | std::uint32_t{c[2]};
      std::memcpy(record, piece.points[i].data(), 3 * sizeof(float));
      std::memcpy(record + 12, &rgba, sizeof(rgba));
    }
    out.write(block.data(), static_cast<std::streamsize>(block.size()));
    written += piece.n;
  });
  out.close();
  if (written != points) {
    throw MappingError(path + ": " + std::to_string(points) + " points announced, " +
                       std::to_string(written) + " came");
  }
  if (!out) throw MappingError(path + ": PCD write failed");
}

/// Writes <dir>/cloud.ply and <dir>/cloud.pcd (binary) of the `points` points that `pieces`
/// hands over, each atomically, one on each of two threads, without a copy of the whole cloud.
inline void saveCloudPlyPcd(std::size_t points, const CloudPieces& pieces, const std::string& dir) {
  std::filesystem::create_directories(dir);
  const std::string base = (std::filesystem::path(dir) / "cloud").string();
  inTwo([&](int file) {
    if (file == 0) {
      writeAtomically(base + ".pcd",
                      [&](const std::string& tmp) { writePcdBinary(tmp, points, pieces); });
      return;
    }
    writeAtomically(base + ".ply", [&](const std::string& tmp) {
      PlyWriter ply(tmp, points, /*colours=*/true);
      pieces([&ply](const CloudPiece& p) { ply.addVertices(p.points, p.colors, p.n); });
      ply.close();
    });
  });
}

/// The same for a PCL cloud (handed over in pieces of 64 Ki points).
inline void saveCloudPlyPcd(const pcl::PointCloud<pcl::PointXYZRGB>& cloud,
                            const std::string& dir) {
  const auto pieces = [&cloud](const std::function<void(const CloudPiece&)>& emit) {
    constexpr std::size_t kPiece = std::size_t{1} << 16;
    std::vector<Eigen::Vector3f> points;
    std::vector<std::array<std::uint8_t, 3>> colors;
    for (std::size_t begin = 0; begin < cloud.size(); begin += kPiece) {
      const std::size_t end = std::min(cloud.size(), begin + kPiece);
      points.clear();
      colors.clear();
      for (std::size_t i = begin; i < end; ++i) {
        points.emplace_back(cloud[i].x, cloud[i].y, cloud[i].z);
        colors.push_back({cloud[i].r, cloud[i].g, cloud[i].b});
      }
      emit({points.data(), colors.data(), points.size()});
    }
  };
  saveCloudPlyPcd(cloud.size(), pieces, dir);
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
