#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace dynamap {

/// Sorts `items` by the 64-bit `key(item)`, items of equal keys keeping their order (a stable
/// sort: items made in index order come out as std::sort orders (key, index)), in a few linear
/// passes, least significant byte first; a byte that every key shares is skipped. `scratch` is
/// reused between calls. For the voxel keys of a keyframe's points: 2-3 x faster than std::sort.
template <typename T, typename KeyFn>
void radixSortByKey(std::vector<T>& items, std::vector<T>& scratch, const KeyFn& key) {
  scratch.resize(items.size());
  for (int shift = 0; shift < 64; shift += 8) {
    std::array<std::size_t, 257> start{};
    for (const T& item : items) ++start[((key(item) >> shift) & 0xff) + 1];
    bool one_bucket = false;
    for (int b = 1; b <= 256; ++b) one_bucket = one_bucket || start[b] == items.size();
    if (one_bucket) continue;
    for (int b = 0; b < 256; ++b) start[b + 1] += start[b];
    for (const T& item : items) scratch[start[(key(item) >> shift) & 0xff]++] = item;
    items.swap(scratch);
  }
}

}  // namespace dynamap
