// dynamap/mapping/flat_index.hpp: the same answers as std::unordered_map, through its growth.
#include <gtest/gtest.h>

#include <random>
#include <unordered_map>

#include "dynamap/mapping/flat_index.hpp"

namespace dynamap::test {
namespace {

TEST(FlatIndex, AnswersAsUnorderedMapForVoxelKeysThroughGrowth) {
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> axis(-40, 40);  // many repeats: ~530 k cells, 200 k draws
  const auto key = [&] {
    const auto c = [&] { return static_cast<std::uint64_t>(axis(rng) + (1 << 20)); };
    return c() | (c() << 21) | (c() << 42);  // as voxelKey() packs them
  };
  FlatIndex index(4);  // grows many times
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
    EXPECT_EQ(index.find(k), it == reference.end() ? FlatIndex::kMissing : it->second);
  }
  // Keys 0 and neighbours of the reserved empty key are ordinary keys.
  EXPECT_EQ(index.find(0), FlatIndex::kMissing);
  EXPECT_TRUE(index.tryEmplace(0, 7).second);
  EXPECT_EQ(index.find(0), 7u);
  EXPECT_TRUE(index.tryEmplace(FlatIndex::kEmpty - 1, 8).second);
  EXPECT_EQ(index.find(FlatIndex::kEmpty - 1), 8u);
}

}  // namespace
}  // namespace dynamap::test
