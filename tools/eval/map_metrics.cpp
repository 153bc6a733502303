#include "map_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "dynamap/mapping/ply_io.hpp"
#include "dynamap/mapping/voxel_key.hpp"

namespace dynamap {
namespace {

constexpr std::uint32_t kLeafSize = 8;
constexpr double kCoarseDiagonal = 1.7321 * ReferenceClouds::kCoarseVoxelM + 1e-4;

std::uint64_t packCell(const Eigen::Vector3i& c) { return packVoxelKey(c.x(), c.y(), c.z()); }

// Runs fn(i) for i in [0, n) with TBB. fn writes only its own index's slot; the sums are taken
// afterwards in index order, so the results do not depend on the threads.
template <typename Fn>
void parallelFor(std::size_t n, const Fn& fn) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) fn(i);
  });
}

// Voxel key of a point (21 bits per axis, wrapping); `cell` receives the integer voxel.
std::uint64_t voxelKey(const Eigen::Vector3f& p, double inv, Eigen::Vector3i* cell = nullptr) {
  Eigen::Vector3i c;
  for (int a = 0; a < 3; ++a) {
    // Clamped before the cast (a far point would overflow); keys wrap at 2^21 voxels.
    c[a] = static_cast<int>(std::clamp(std::floor(p[a] * inv), -1e9, 1e9));
  }
  if (cell != nullptr) *cell = c;
  return packCell(c);
}

// How many of `points` have a point of `index` within `radius` (of a k-d tree, in parallel).
std::size_t countWithin(const PointIndex& index, const std::vector<Eigen::Vector3f>& points,
                        float radius) {
  std::vector<char> within(points.size(), 0);
  parallelFor(points.size(), [&](std::size_t i) {
    within[i] = index.nearestDistance(points[i], radius) <= radius ? 1 : 0;
  });
  std::size_t n = 0;
  for (const char c : within) n += c;
  return n;
}

// The ghosts off the settled reference, and its points the map covers (MapMetrics).
void addSettledMetrics(const PointIndex& map_index,
                       const std::vector<Eigen::Vector3f>& ghost_points,
                       const ReferenceClouds& refs, const MapMetricsOptions& options,
                       MapMetrics* m) {
  const auto ghost_thr = static_cast<float>(options.ghost_dynamic_m);
  const std::size_t at_place = countWithin(*refs.settled_ref, ghost_points, ghost_thr);
  m->path_ghost_ratio = static_cast<double>(ghost_points.size() - at_place) / map_index.size();
  m->settled_completeness =
      static_cast<double>(
          countWithin(map_index, refs.settled_points, static_cast<float>(options.threshold_m))) /
      refs.settled_points.size();
}

}  // namespace

PointIndex::PointIndex(std::vector<Eigen::Vector3f> points) : points_(std::move(points)) {
  nodes_.reserve(2 * points_.size() / kLeafSize + 2);
  if (!points_.empty()) build(0, static_cast<std::uint32_t>(points_.size()));
}

std::uint32_t PointIndex::build(std::uint32_t begin, std::uint32_t end) {
  const auto id = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  Eigen::Vector3f lo = points_[begin], hi = points_[begin];
  for (std::uint32_t i = begin; i < end; ++i) {
    lo = lo.cwiseMin(points_[i]);
    hi = hi.cwiseMax(points_[i]);
  }
  nodes_[id].lo = lo;
  nodes_[id].hi = hi;
  if (end - begin <= kLeafSize) {
    nodes_[id].begin = begin;
    nodes_[id].end = end;
    return id;
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(
      points_.begin() + begin, points_.begin() + mid, points_.begin() + end,
      [axis](const Eigen::Vector3f& a, const Eigen::Vector3f& b) { return a[axis] < b[axis]; });
  const std::uint32_t left = build(begin, mid);
  const std::uint32_t right = build(mid, end);
  nodes_[id].axis = axis;
  nodes_[id].left = left;
  nodes_[id].right = right;
  return id;
}

// Exact nearest neighbour, nearer child first, a subtree pruned by the distance from q to the
// bounding box of its points. (Bounds from the split planes alone are open on the cells' other
// sides: a query far from the cloud then scanned much of it, 3 s of a crowd map's metrics.)
void PointIndex::search(std::uint32_t node, const Eigen::Vector3f& q, float* best_sq) const {
  const Node& n = nodes_[node];
  if (n.axis < 0) {
    for (std::uint32_t i = n.begin; i < n.end; ++i) {
      *best_sq = std::min(*best_sq, (points_[i] - q).squaredNorm());
    }
    return;
  }
  const auto box_sq = [&](std::uint32_t child) {
    const Node& c = nodes_[child];
    return (c.lo - q).cwiseMax(q - c.hi).cwiseMax(0.0f).squaredNorm();
  };
  std::uint32_t first = n.left, second = n.right;
  float first_sq = box_sq(first), second_sq = box_sq(second);
  if (second_sq < first_sq) std::swap(first, second), std::swap(first_sq, second_sq);
  if (first_sq < *best_sq) search(first, q, best_sq);
  if (second_sq < *best_sq) search(second, q, best_sq);
}

float PointIndex::nearestDistance(const Eigen::Vector3f& q, float max_distance) const {
  if (points_.empty()) return std::numeric_limits<float>::infinity();
  float best = std::isfinite(max_distance) ? max_distance * max_distance * 1.0001f
                                           : std::numeric_limits<float>::infinity();
  search(0, q, &best);
  const float d = std::sqrt(best);
  return d <= max_distance ? d : std::numeric_limits<float>::infinity();
}

std::vector<Eigen::Vector3f> voxelCentroids(const std::vector<Eigen::Vector3f>& points,
                                            double voxel_m) {
  struct Acc {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int n = 0;
  };
  std::unordered_map<std::uint64_t, Acc> voxels;
  voxels.reserve(points.size() / 2);
  const double inv = 1.0 / voxel_m;
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    Acc& a = voxels[voxelKey(p, inv)];
    a.sum += p.cast<double>();
    ++a.n;
  }
  std::vector<Eigen::Vector3f> out;
  out.reserve(voxels.size());
  for (const auto& kv : voxels) out.emplace_back((kv.second.sum / kv.second.n).cast<float>());
  return out;
}

std::vector<std::size_t> connectedGroups(const std::vector<Eigen::Vector3f>& points, double voxel_m,
                                         std::size_t min_points) {
  const double inv = 1.0 / voxel_m;
  std::unordered_map<std::uint64_t, std::pair<Eigen::Vector3i, std::size_t>> cells;  // points
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    Eigen::Vector3i c;
    const std::uint64_t k = voxelKey(p, inv, &c);
    auto [it, inserted] = cells.try_emplace(k, c, 0);
    ++it->second.second;
  }
  std::vector<std::size_t> groups;
  std::vector<std::uint64_t> stack;
  while (!cells.empty()) {
    std::size_t size = 0;
    stack.assign(1, cells.begin()->first);
    while (!stack.empty()) {  // flood fill, erasing visited cells
      const auto it = cells.find(stack.back());
      stack.pop_back();
      if (it == cells.end()) continue;
      const Eigen::Vector3i c = it->second.first;
      size += it->second.second;
      cells.erase(it);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const std::uint64_t n = packCell(c + Eigen::Vector3i(dx, dy, dz));
            if (cells.count(n) != 0) stack.push_back(n);
          }
    }
    if (size >= min_points) groups.push_back(size);
  }
  return groups;
}

std::vector<Eigen::Vector3f> readPlyVertices(const std::string& path) {
  return readPly(path).vertices;
}

ReferenceClouds loadReferenceClouds(const std::string& dir) {
  namespace fs = std::filesystem;
  ReferenceClouds refs;
  refs.static_points = readPlyVertices((fs::path(dir) / "reference_static.ply").string());
  refs.static_ref = std::make_shared<PointIndex>(refs.static_points);
  refs.static_coarse = std::make_shared<PointIndex>(
      voxelCentroids(refs.static_points, ReferenceClouds::kCoarseVoxelM));
  const fs::path dyn = fs::path(dir) / "reference_dynamic.ply";
  if (fs::exists(dyn))
    refs.dynamic_ref = std::make_shared<PointIndex>(readPlyVertices(dyn.string()));
  const fs::path settled = fs::path(dir) / "reference_settled.ply";
  if (fs::exists(settled)) {
    refs.settled_points = readPlyVertices(settled.string());
    refs.settled_ref = std::make_shared<PointIndex>(refs.settled_points);
  }
  return refs;
}

MapMetrics computeMapMetrics(const std::vector<Eigen::Vector3f>& map_points_W,
                             const ReferenceClouds& refs, const Eigen::Isometry3d& T_ref_map,
                             const MapMetricsOptions& options) {
  std::vector<Eigen::Vector3f> moved;
  moved.reserve(map_points_W.size());
  const Eigen::Isometry3f T = T_ref_map.cast<float>();
  for (const auto& p : map_points_W) moved.push_back(T * p);
  const std::vector<Eigen::Vector3f> map = voxelCentroids(moved, options.voxel_m);
  MapMetrics m;
  m.map_points = map.size();
  if (map.empty() || !refs.static_ref) return m;
  const auto thr = static_cast<float>(options.threshold_m);
  const auto ghost_thr = static_cast<float>(options.ghost_dynamic_m);
  std::vector<float> d_static(map.size());
  std::vector<char> ghost(map.size(), 0);
  parallelFor(map.size(), [&](std::size_t i) {
    d_static[i] = refs.static_ref->nearestDistance(map[i], thr);
    if (!std::isfinite(d_static[i])) {
      // Far from the scene: the coarse reference bounds the exact search (a centroid lies
      // within one coarse voxel diagonal of a reference point).
      const float bound = refs.static_coarse ? refs.static_coarse->nearestDistance(map[i]) +
                                                   static_cast<float>(kCoarseDiagonal)
                                             : std::numeric_limits<float>::infinity();
      d_static[i] = options.exact_far_distances || !refs.static_coarse
                        ? refs.static_ref->nearestDistance(map[i], bound)
                        : std::max(bound - static_cast<float>(kCoarseDiagonal), thr * 1.0001f);
    }
    if (d_static[i] > thr && refs.dynamic_ref) {
      ghost[i] = refs.dynamic_ref->nearestDistance(map[i], ghost_thr) <= ghost_thr ? 1 : 0;
    }
  });
  double sum = 0.0;
  std::size_t close = 0, ghosts = 0;
  for (std::size_t i = 0; i < map.size(); ++i) {
    sum += d_static[i];
    close += d_static[i] <= thr ? 1 : 0;
    ghosts += ghost[i];
  }
  m.accuracy_mean_m = sum / map.size();
  m.precision = static_cast<double>(close) / map.size();
  m.ghost_ratio = static_cast<double>(ghosts) / map.size();
  std::vector<Eigen::Vector3f> ghost_points;
  ghost_points.reserve(ghosts);
  for (std::size_t i = 0; i < map.size(); ++i) {
    if (ghost[i] != 0) ghost_points.push_back(map[i]);
  }
  const auto min_points = static_cast<std::size_t>(std::max(1, options.ghost_fragment_min_points));
  for (const std::size_t n : connectedGroups(ghost_points, options.voxel_m, min_points)) {
    ++m.ghost_fragments;
    m.ghost_fragment_points += n;
  }
  const bool settled = refs.settled_ref && !refs.settled_points.empty();
  if (!options.completeness && !settled) return m;
  const PointIndex map_index(map);
  if (settled) addSettledMetrics(map_index, ghost_points, refs, options, &m);
  if (!options.completeness) return m;
  m.completeness = refs.static_points.empty()
                       ? 0.0
                       : static_cast<double>(countWithin(map_index, refs.static_points, thr)) /
                             refs.static_points.size();
  const double ps = m.precision + m.completeness;
  m.fscore = ps > 0 ? 2.0 * m.precision * m.completeness / ps : 0.0;
  return m;
}

}  // namespace dynamap
