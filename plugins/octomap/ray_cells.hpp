#pragma once

#include <vector>

#include <octomap/OcTree.h>
#include <Eigen/Geometry>

namespace dynamap::plugin {

/// The cells one scan updates, as OctoMap's OccupancyOcTreeBase::computeUpdate() finds them:
/// free, the cells its rays cross (cut at `max_range_m` when that is >= 0); occupied, the end
/// points' within that range; a cell in both is occupied only. Each cell once, in the Morton
/// order of the keys (deterministic; the octree's depth-first order, so that updates one after
/// the other share most of their path from the root: a third less time in the tree's updates on
/// the Bonn slice x10, the same map, as each cell gets one update per scan). Collected in flat
/// hash tables, not OctoMap's node-based unordered_set of keys, whose allocations, rehashing and
/// freeing took a third of a keyframe's integration.
struct RayCells {
  std::vector<octomap::OcTreeKey> free, occupied;
};

/// A cell's net log-odds change; taken_back: the cell is one of the view taken out (a change that
/// brings it back to unknown deletes it).
struct CellChange {
  octomap::OcTreeKey key;
  float log_odds = 0.0f;
  bool taken_back = false;
};

/// What taking `from` out and putting `to` in changes, cell by cell: +hit / +miss for the
/// occupied / free cells of `to`, minus the same for those of `from`; cells whose changes cancel
/// (a cell free or occupied in both) left out. Cells of `from` first, each in the order first met.
/// `part` of `parts`: only the cells a hash of the key puts in that part (the parts are disjoint
/// and together all cells), so that the parts can be netted on different threads.
std::vector<CellChange> netChange(const RayCells& from, const RayCells& to, float hit_log_odds,
                                  float miss_log_odds, int part = 0, int parts = 1);

/// `tree` gives the key grid and the ray traversal (OcTree::computeRayKeys()); only read.
RayCells castRays(const octomap::OcTree& tree, const octomap::Pointcloud& scan,
                  const octomap::point3d& origin, double max_range_m);

/// The centres of the distinct cells of `tree`'s key grid that the points (camera frame, moved
/// by T_W_C) fall in, each once, in the order first met; points outside the grid are dropped.
/// (The same cloud as collecting the keys in an octomap::KeySet, without its per-key nodes.)
octomap::Pointcloud distinctCellCentres(const octomap::OcTree& tree,
                                        const std::vector<Eigen::Vector3f>& points_C,
                                        const Eigen::Isometry3f& T_W_C);

}  // namespace dynamap::plugin
