// dynamap/mapping/flat_index.hpp and voxel_block_index.hpp: the same answers as
// std::unordered_map, through their growth.
#include <gtest/gtest.h>

#include <array>
#include <random>
#include <unordered_map>

#include "dynamap/mapping/flat_index.hpp"
#include "dynamap/mapping/voxel_block_index.hpp"
#include "dynamap/mapping/voxel_key.hpp"

namespace dynamap::test {
namespace {

/// Fills `index` with 200 k draws of `key()` beside an unordered_map, then probes 100 k more:
/// every insertion and every lookup answers as the map does.
template <typename Index, typename KeyFn>
void expectAnswersAsUnorderedMap(Index& index, KeyFn&& key) {
  std::unordered_map<std::uint64_t, std::uint32_t> reference;
  for (std::uint32_t i = 0; i < 200000; ++i) {
    const std::uint64_t k = key();
    const auto [value, inserted] = index.tryEmplace(k, i);
    const auto [it, ref_inserted] = reference.try_emplace(k, i);
    ASSERT_EQ(inserted, ref_inserted);
    ASSERT_EQ(value, it->second);
  }
  EXPECT_EQ(index.size(), reference.size());
  for (int probe = 0; probe < 100000; ++probe) {
    const std::uint64_t k = key();
    const auto it = reference.find(k);
    EXPECT_EQ(index.find(k), it == reference.end() ? Index::kMissing : it->second);
  }
}

TEST(FlatIndex, AnswersAsUnorderedMapForVoxelKeysThroughGrowth) {
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> axis(-40, 40);  // many repeats: ~530 k cells, 200 k draws
  const auto key = [&] {
    const auto c = [&] { return static_cast<std::uint64_t>(axis(rng) + (1 << 20)); };
    return c() | (c() << 21) | (c() << 42);  // as voxelKey() packs them
  };
  FlatIndex index(4);  // grows many times
  expectAnswersAsUnorderedMap(index, key);
  // Keys 0 and neighbours of the reserved empty key are ordinary keys.
  EXPECT_EQ(index.find(0), FlatIndex::kMissing);
  EXPECT_TRUE(index.tryEmplace(0, 7).second);
  EXPECT_EQ(index.find(0), 7u);
  EXPECT_TRUE(index.tryEmplace(FlatIndex::kEmpty - 1, 8).second);
  EXPECT_EQ(index.find(FlatIndex::kEmpty - 1), 8u);
}

TEST(VoxelBlockIndex, AnswersAsUnorderedMapForCellsAcrossBlocksAndTheWrap) {
  std::mt19937_64 rng(12);
  std::uniform_int_distribution<int> axis(-30, 30);  // block edges at multiples of 4, and 0
  std::uniform_int_distribution<int> far(0, 9);      // some cells at the keys' wrap, +-2^20
  const auto cell = [&] {
    const int wrap = far(rng) == 0 ? (1 << 20) : 0;
    return static_cast<std::int64_t>(axis(rng) + wrap);
  };
  VoxelBlockIndex index(4);  // its blocks and cells grow many times
  expectAnswersAsUnorderedMap(index, [&] { return packVoxelKey(cell(), cell(), cell()); });
}

TEST(VoxelBlockIndex, BlocksAreTheAlignedFourCubedCells) {
  const std::uint64_t block = VoxelBlockIndex::blockOf(packVoxelKey(-4, 8, 0));
  for (int x = -4; x < 0; ++x) {
    for (int y = 8; y < 12; ++y) {
      for (int z = 0; z < 4; ++z) EXPECT_EQ(VoxelBlockIndex::blockOf(packVoxelKey(x, y, z)), block);
    }
  }
  for (const auto& [x, y, z] : {std::array<int, 3>{-5, 8, 0}, {0, 8, 0}, {-4, 7, 0}, {-4, 12, 0},
                                {-4, 8, -1}, {-4, 8, 4}}) {
    EXPECT_NE(VoxelBlockIndex::blockOf(packVoxelKey(x, y, z)), block) << x << " " << y << " " << z;
  }
}

}  // namespace
}  // namespace dynamap::test
