// dynamap/mapping/radix_sort.hpp: the order std::sort gives (key, index) pairs made in index order.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "dynamap/mapping/radix_sort.hpp"

namespace dynamap::test {
namespace {

using Pairs = std::vector<std::pair<std::uint64_t, std::uint32_t>>;
const auto first = [](const std::pair<std::uint64_t, std::uint32_t>& p) { return p.first; };

Pairs indexed(const std::vector<std::uint64_t>& keys) {
  Pairs p(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) p[i] = {keys[i], static_cast<std::uint32_t>(i)};
  return p;
}

TEST(RadixSort, GivesStdSortsOrderForVoxelKeysWithManyDuplicates) {
  std::mt19937_64 rng(7);
  Pairs scratch;
  for (const int spread : {1, 50, 3000}) {  // few distinct voxels ... many
    std::uniform_int_distribution<int> axis(-spread, spread);
    std::vector<std::uint64_t> keys(20000);
    for (auto& k : keys) {  // 21 bits per axis, as voxelKey() packs them
      const auto c = [&] { return static_cast<std::uint64_t>(axis(rng) + (1 << 20)); };
      k = c() | (c() << 21) | (c() << 42);
    }
    Pairs expected = indexed(keys), got = indexed(keys);
    std::sort(expected.begin(), expected.end());
    radixSortByKey(got, scratch, first);
    EXPECT_EQ(got, expected) << spread;
  }
  Pairs empty;
  radixSortByKey(empty, scratch, first);
  EXPECT_TRUE(empty.empty());
  Pairs extremes = indexed({~0ULL, 0ULL, ~0ULL, 1ULL << 63});
  radixSortByKey(extremes, scratch, first);
  EXPECT_EQ(extremes, (Pairs{{0ULL, 1}, {1ULL << 63, 3}, {~0ULL, 0}, {~0ULL, 2}}));
}

}  // namespace
}  // namespace dynamap::test
