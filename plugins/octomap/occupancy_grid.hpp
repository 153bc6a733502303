#pragma once

#include <string>

#include <octomap/OcTree.h>

namespace dynamap::plugin {

/// Which world axis is "up" (0 = x, 1 = y, 2 = z; sign -1 for -x/-y/-z) and the height band
/// whose cells are projected into the 2D grid.
/// |log-odds| below this: a cell no view sees any more (one taken out by deintegrate(), which
/// cannot always delete it); the grid leaves it unknown. (A hit is 0.85, a miss 0.41.)
inline constexpr float kUnknownLogOdds = 1e-3f;

struct GridOptions {
  int up_axis = 2;
  int up_sign = 1;
  double min_height_m = 0.1;
  double max_height_m = 2.0;
};

/// Writes <dir>/grid.pgm and <dir>/grid.yaml in the ROS map_server layout (occupied 0, free 254,
/// unknown 205; origin = world position of the lower-left pixel). Grid axes: for up = z the
/// world (x, y); for up = y the world (z, x); for up = x the world (y, z). A cell is occupied if
/// any occupied voxel of the band projects into it, free if only free voxels do.
void writeOccupancyGrid(const octomap::OcTree& tree, const GridOptions& options,
                        const std::string& dir);

}  // namespace dynamap::plugin
