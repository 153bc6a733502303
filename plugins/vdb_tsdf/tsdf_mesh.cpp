#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "dynamap/core/rounding.hpp"
#include "tsdf_volume.hpp"

namespace dynamap::plugin {
namespace {

// True when all 8 voxels of the cell holding index-space point q weigh more than min_weight:
// drops the spurious faces between observed and never-observed voxels.
template <typename Accessor>
bool cellObserved(Accessor& weights, const openvdb::Vec3s& q, float min_weight) {
  const openvdb::Coord base(static_cast<int>(std::floor(q.x())),
                            static_cast<int>(std::floor(q.y())),
                            static_cast<int>(std::floor(q.z())));
  for (int dx = 0; dx < 2; ++dx) {
    for (int dy = 0; dy < 2; ++dy) {
      for (int dz = 0; dz < 2; ++dz) {
        if (!(weights.getValue(base.offsetBy(dx, dy, dz)) > min_weight)) return false;
      }
    }
  }
  return true;
}

}  // namespace

PlyData TsdfVolume::extractMesh(const openvdb::FloatGrid& voted) const {
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(voted, points, triangles, quads, 0.0, 0.0);

  // Per vertex, on TBB's threads (each with its own accessors): whether its cell was observed,
  // and its colour. Then faces and vertices in their order, on this thread.
  const float inv_voxel = static_cast<float>(1.0 / options_.voxel_size_m);
  std::vector<char> keep_vertex(points.size());
  std::vector<std::array<std::uint8_t, 3>> vertex_colors(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096), [&](const auto& r) {
    auto weights = weight_->getConstAccessor();
    auto colors = color_->getConstAccessor();
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const openvdb::Vec3s q = points[i] * inv_voxel;
      keep_vertex[i] = cellObserved(weights, q, options_.min_weight) ? 1 : 0;
      if (!keep_vertex[i]) continue;
      const openvdb::Vec3s c = colors.getValue(openvdb::Coord(
          int(roundHalfAway(q.x())), int(roundHalfAway(q.y())), int(roundHalfAway(q.z()))));
      vertex_colors[i] = {static_cast<std::uint8_t>(std::clamp(c.x(), 0.0f, 255.0f)),
                          static_cast<std::uint8_t>(std::clamp(c.y(), 0.0f, 255.0f)),
                          static_cast<std::uint8_t>(std::clamp(c.z(), 0.0f, 255.0f))};
    }
  });
  std::vector<std::array<std::uint32_t, 3>> faces;
  faces.reserve(triangles.size() + 2 * quads.size());
  auto addTriangle = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    if (keep_vertex[a] && keep_vertex[b] && keep_vertex[c]) faces.push_back({a, b, c});
  };
  // volumeToMesh winds faces for a level set (negative inside); flip so normals face the camera.
  for (const auto& t : triangles) addTriangle(t[2], t[1], t[0]);
  for (const auto& q : quads) {
    addTriangle(q[3], q[2], q[1]);
    addTriangle(q[3], q[1], q[0]);
  }

  PlyData mesh;
  std::vector<std::int64_t> remap(points.size(), -1);
  for (auto& f : faces) {
    for (auto& idx : f) {
      if (remap[idx] < 0) {
        remap[idx] = static_cast<std::int64_t>(mesh.vertices.size());
        const openvdb::Vec3s& p = points[idx];
        mesh.vertices.emplace_back(p.x(), p.y(), p.z());
        mesh.colors.push_back(vertex_colors[idx]);
      }
      idx = static_cast<std::uint32_t>(remap[idx]);
    }
  }
  mesh.triangles = std::move(faces);
  return mesh;
}

}  // namespace dynamap::plugin
