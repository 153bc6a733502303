#include "ray_cells.hpp"

#include <algorithm>
#include <cstdint>

#include "dynamap/mapping/flat_index.hpp"

namespace dynamap::plugin {
namespace {

std::uint64_t packed(const octomap::OcTreeKey& k) {
  return std::uint64_t{k[0]} | std::uint64_t{k[1]} << 16 | std::uint64_t{k[2]} << 32;
}

/// Appends `key` to `out` unless `seen` has it.
void addOnce(const octomap::OcTreeKey& key, FlatIndex& seen, std::vector<octomap::OcTreeKey>& out) {
  if (seen.tryEmplace(packed(key), 0).second) out.push_back(key);
}

/// The key's bits interleaved (a Morton code): keys in this order walk the octree depth first,
/// so that consecutive updates share most of their path from the root.
std::uint64_t mortonCode(const octomap::OcTreeKey& k) {
  const auto spread = [](std::uint64_t x) {  // 16 bits to every third bit
    x &= 0xFFFF;
    x = (x | x << 16) & 0x0000FF0000FFull;
    x = (x | x << 8) & 0x00F00F00F00Full;
    x = (x | x << 4) & 0x0C30C30C30C3ull;
    x = (x | x << 2) & 0x249249249249ull;
    return x;
  };
  return spread(k[0]) | spread(k[1]) << 1 | spread(k[2]) << 2;
}

void sortByMortonCode(std::vector<octomap::OcTreeKey>& keys) {
  std::vector<std::pair<std::uint64_t, octomap::OcTreeKey>> coded;
  coded.reserve(keys.size());
  for (const octomap::OcTreeKey& k : keys) coded.emplace_back(mortonCode(k), k);
  std::sort(coded.begin(), coded.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (std::size_t i = 0; i < keys.size(); ++i) keys[i] = coded[i].second;
}

}  // namespace

RayCells castRays(const octomap::OcTree& tree, const octomap::Pointcloud& scan,
                  const octomap::point3d& origin, double max_range_m) {
  RayCells cells;
  FlatIndex free_seen(8 * scan.size()), occupied_seen(scan.size());
  octomap::KeyRay ray;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const octomap::point3d& p = scan[i];
    const bool in_range = max_range_m < 0.0 || (p - origin).norm() <= max_range_m;
    const octomap::point3d end =
        in_range ? p : origin + (p - origin).normalized() * static_cast<float>(max_range_m);
    if (tree.computeRayKeys(origin, end, ray)) {
      for (const octomap::OcTreeKey& key : ray) addOnce(key, free_seen, cells.free);
    }
    octomap::OcTreeKey key;
    if (in_range && tree.coordToKeyChecked(p, key)) addOnce(key, occupied_seen, cells.occupied);
  }
  // Occupied wins over free.
  std::size_t kept = 0;
  for (const octomap::OcTreeKey& key : cells.free) {
    if (occupied_seen.find(packed(key)) == FlatIndex::kMissing) cells.free[kept++] = key;
  }
  cells.free.resize(kept);
  sortByMortonCode(cells.free);
  sortByMortonCode(cells.occupied);
  return cells;
}

std::vector<CellChange> netChange(const RayCells& from, const RayCells& to, float hit_log_odds,
                                  float miss_log_odds, int part, int parts) {
  const auto n_parts = static_cast<unsigned>(std::max(1, parts));
  // The cells of this part: a hash of the key other than FlatIndex's slot hash.
  const auto mine = [&](std::uint64_t k) {
    return ((k * 0xD6E8FEB86659FD93ull) >> 32) % n_parts == static_cast<unsigned>(part);
  };
  const std::size_t from_cells = from.free.size() + from.occupied.size();
  std::vector<CellChange> change;
  change.reserve(from_cells / n_parts + 1024);
  // Most of `to`'s cells are `from`'s: the table grows if not.
  FlatIndex index(from_cells * 5 / 4 / n_parts + 1024);
  const auto add = [&](const std::vector<octomap::OcTreeKey>& keys, float log_odds,
                       bool taken_back) {
    for (const octomap::OcTreeKey& key : keys) {
      const std::uint64_t k = packed(key);
      if (!mine(k)) continue;
      const auto [i, inserted] = index.tryEmplace(k, static_cast<std::uint32_t>(change.size()));
      if (inserted) {
        change.push_back({key, log_odds, taken_back});
      } else {
        change[i].log_odds += log_odds;
      }
    }
  };
  add(from.free, -miss_log_odds, true);
  add(from.occupied, -hit_log_odds, true);
  add(to.free, miss_log_odds, false);
  add(to.occupied, hit_log_odds, false);
  // A cell's sum cancels exactly when it is the same kind in both (x - x); a free cell of one
  // and an occupied cell of the other keep hit - miss.
  std::size_t kept = 0;
  for (const CellChange& c : change) {
    if (c.log_odds != 0.0f) change[kept++] = c;
  }
  change.resize(kept);
  return change;
}

octomap::Pointcloud distinctCellCentres(const octomap::OcTree& tree,
                                        const std::vector<Eigen::Vector3f>& points_C,
                                        const Eigen::Isometry3f& T_W_C) {
  octomap::Pointcloud cloud;
  cloud.reserve(points_C.size());
  FlatIndex seen(points_C.size() / 4 + 16);  // grows if needed
  for (const auto& p_C : points_C) {
    const Eigen::Vector3f p = T_W_C * p_C;
    octomap::OcTreeKey key;
    if (!tree.coordToKeyChecked(p.x(), p.y(), p.z(), key)) continue;
    if (seen.tryEmplace(packed(key), 0).second) cloud.push_back(tree.keyToCoord(key));
  }
  return cloud;
}

}  // namespace dynamap::plugin
