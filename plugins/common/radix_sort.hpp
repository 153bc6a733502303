#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace dynamap::plugin {

/// Sorts (key, index) pairs by key, pairs of equal keys keeping their order: for pairs made in
/// index order, the order std::sort gives them, in a few linear passes (least significant byte
/// first; a byte that every key shares is skipped). `scratch` is reused between calls.
inline void radixSortByKey(std::vector<std::pair<std::uint64_t, std::uint32_t>>& pairs,
                           std::vector<std::pair<std::uint64_t, std::uint32_t>>& scratch) {
  scratch.resize(pairs.size());
  for (int shift = 0; shift < 64; shift += 8) {
    std::array<std::uint32_t, 257> start{};
    for (const auto& p : pairs) ++start[((p.first >> shift) & 0xff) + 1];
    bool one_bucket = false;
    for (int b = 1; b <= 256; ++b) one_bucket = one_bucket || start[b] == pairs.size();
    if (one_bucket) continue;
    for (int b = 0; b < 256; ++b) start[b + 1] += start[b];
    for (const auto& p : pairs) scratch[start[(p.first >> shift) & 0xff]++] = p;
    pairs.swap(scratch);
  }
}

}  // namespace dynamap::plugin
