// The pcl_voxel backend's compact per-keyframe voxels (plugins/pcl_voxel/keyframe_voxels.hpp):
// centroids, colours and counts come back, from RAM and from the spill file.
#include <gtest/gtest.h>

#include "keyframe_voxels.hpp"

namespace dynamap {
namespace {

plugin::VoxelAccum voxelOf(const Eigen::Vector3f& p, std::uint8_t grey, std::uint32_t n) {
  plugin::VoxelAccum a;
  const std::uint8_t rgb[3] = {grey, static_cast<std::uint8_t>(grey / 2), 7};
  a.add(p, rgb, n);
  return a;
}

struct Unpacked {
  Eigen::Vector3f p;
  std::array<std::uint8_t, 3> rgb;
  std::uint32_t n;
};

std::vector<Unpacked> unpack(const plugin::KeyframeVoxels& v) {
  std::vector<Unpacked> out;
  std::vector<plugin::CompactVoxel> buffer;
  v.forEach(buffer, [&](const Eigen::Vector3f& p, const std::uint8_t* rgb, std::uint32_t n) {
    out.push_back({p, {rgb[0], rgb[1], rgb[2]}, n});
  });
  return out;
}

TEST(KeyframeVoxels, CentroidsColoursAndCountsComeBack) {
  const std::vector<plugin::VoxelAccum> in = {voxelOf({0.1234f, -0.5f, 1.9876f}, 200, 3),
                                              voxelOf({-2.0f, 1.5f, 14.25f}, 17, 70000)};
  const plugin::KeyframeVoxels v(in);
  EXPECT_EQ(v.bytes(), 2 * sizeof(plugin::CompactVoxel));
  const auto out = unpack(v);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_LE((out[0].p - Eigen::Vector3f(0.1234f, -0.5f, 1.9876f)).norm(), 1e-6f);
  EXPECT_LE((out[1].p - Eigen::Vector3f(-2.0f, 1.5f, 14.25f)).norm(), 1e-5f);
  EXPECT_EQ(out[0].rgb, (std::array<std::uint8_t, 3>{200, 100, 7}));
  EXPECT_EQ(out[0].n, 3u);
  EXPECT_EQ(out[1].n, 65535u);  // saturated, not wrapped
}

TEST(KeyframeVoxels, SpilledVoxelsReadBackTheSameAndLeaveRam) {
  const std::vector<plugin::VoxelAccum> in = {voxelOf({0.1f, 0.2f, 0.3f}, 9, 4),
                                              voxelOf({-1.0f, 0.5f, 2.5f}, 250, 1)};
  plugin::KeyframeVoxels a(in), b(in);
  const auto before = unpack(a);
  plugin::SpillFile<plugin::CompactVoxel> file;
  a.spill(file);
  b.spill(file);  // a second span after the first
  EXPECT_EQ(a.bytes(), 0u);
  EXPECT_EQ(b.size(), 2u);
  EXPECT_EQ(file.bytes(), static_cast<long long>(4 * sizeof(plugin::CompactVoxel)));
  for (const auto* v : {&a, &b}) {
    const auto after = unpack(*v);
    ASSERT_EQ(after.size(), before.size());
    for (std::size_t i = 0; i < after.size(); ++i) {
      EXPECT_EQ(after[i].p, before[i].p);
      EXPECT_EQ(after[i].rgb, before[i].rgb);
      EXPECT_EQ(after[i].n, before[i].n);
    }
  }
}

}  // namespace
}  // namespace dynamap
