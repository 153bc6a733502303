#include "occupancy_grid.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include "dynamap/mapping/map_backend.hpp"
#include "dynamap/mapping/ply_io.hpp"

namespace dynamap::plugin {
namespace {

constexpr unsigned char kOccupied = 0;
constexpr unsigned char kFree = 254;
constexpr unsigned char kUnknown = 205;

}  // namespace

void writeOccupancyGrid(const octomap::OcTree& tree, const GridOptions& options,
                        const std::string& dir) {
  const int a = options.up_axis;
  const int ai = (a + 1) % 3;  // grid x axis
  const int aj = (a + 2) % 3;  // grid y axis
  const double res = tree.getResolution();
  double min_x = 0, min_y = 0, min_z = 0, max_x = 0, max_y = 0, max_z = 0;
  tree.getMetricMin(min_x, min_y, min_z);
  tree.getMetricMax(max_x, max_y, max_z);
  const double lo[3] = {min_x, min_y, min_z};
  const double hi[3] = {max_x, max_y, max_z};
  const int width = std::max(1, static_cast<int>(std::ceil((hi[ai] - lo[ai]) / res)));
  const int height = std::max(1, static_cast<int>(std::ceil((hi[aj] - lo[aj]) / res)));
  std::vector<unsigned char> cells(static_cast<std::size_t>(width) * height, kUnknown);
  const unsigned max_depth = tree.getTreeDepth();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (std::fabs(it->getLogOdds()) < kUnknownLogOdds) continue;
    const bool occupied = tree.isNodeOccupied(*it);
    const double size = it.getSize();
    const int n = 1 << (max_depth - it.getDepth());  // finest cells per side
    const octomap::point3d c = it.getCoordinate();
    const double p0[3] = {c.x() - size / 2 + res / 2, c.y() - size / 2 + res / 2,
                          c.z() - size / 2 + res / 2};
    for (int k = 0; k < n; ++k) {  // along "up"
      const double h = options.up_sign * (p0[a] + k * res);
      if (h < options.min_height_m || h > options.max_height_m) continue;
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          const int gx = static_cast<int>(std::floor((p0[ai] + i * res - lo[ai]) / res));
          const int gy = static_cast<int>(std::floor((p0[aj] + j * res - lo[aj]) / res));
          if (gx < 0 || gy < 0 || gx >= width || gy >= height) continue;
          unsigned char& cell = cells[static_cast<std::size_t>(height - 1 - gy) * width + gx];
          if (occupied) {
            cell = kOccupied;
          } else if (cell == kUnknown) {
            cell = kFree;
          }
        }
      }
    }
  }
  const std::filesystem::path d(dir);
  writeAtomically((d / "grid.pgm").string(), [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out << "P5\n" << width << " " << height << "\n255\n";
    out.write(reinterpret_cast<const char*>(cells.data()),
              static_cast<std::streamsize>(cells.size()));
    if (!out) throw MappingError(tmp + ": write failed");
  });
  writeAtomically((d / "grid.yaml").string(), [&](const std::string& tmp) {
    const char* names[3] = {"x", "y", "z"};
    std::ofstream out(tmp);
    out << "# dynamap octomap 2D grid: up = " << (options.up_sign < 0 ? "-" : "") << names[a]
        << ", band [" << options.min_height_m << ", " << options.max_height_m
        << "] m; image x = world " << names[ai] << ", image y (up) = world " << names[aj] << "\n"
        << "image: grid.pgm\nresolution: " << res << "\norigin: [" << lo[ai] << ", " << lo[aj]
        << ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
    if (!out) throw MappingError(tmp + ": write failed");
  });
}

}  // namespace dynamap::plugin
