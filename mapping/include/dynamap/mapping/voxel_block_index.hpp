#pragma once
// Voxel keys (packVoxelKey) -> 32-bit values, the cells grouped in 4 x 4 x 4 blocks: a FlatIndex
// finds a block, the block holds its 64 cells' values side by side. Keys that are neighbours in
// space share a block and its cache lines, so a walk over a surface (a keyframe's voxels in key
// order) mostly stays in cache, where a FlatIndex of the voxel keys themselves scatters every
// lookup over the whole table. Not thread-safe for writes.
#include <cstdint>
#include <utility>
#include <vector>

#include "dynamap/mapping/flat_index.hpp"
#include "dynamap/mapping/voxel_key.hpp"

namespace dynamap {

class VoxelBlockIndex {
 public:
  static constexpr std::uint32_t kMissing = FlatIndex::kMissing;
  static constexpr int kCellsPerBlock = 64;

  /// `expected_cells`: distinct keys expected (a surface fills ~1/4 of a block's cells).
  explicit VoxelBlockIndex(std::size_t expected_cells = 1024)
      : blocks_(expected_cells / 16 + 16) {
    cells_.reserve((expected_cells / 16 + 16) * kCellsPerBlock);
  }

  /// The block holding `key`'s cell: the same for the 4 x 4 x 4 cells of an aligned block, and
  /// different from every other block's (the cells' keys wrap as packVoxelKey's do).
  static std::uint64_t blockOf(std::uint64_t key) {
    constexpr std::uint64_t kBlockAxisMask = kVoxelKeyAxisMask >> 2;
    const auto axis = [key](int a) { return (key >> (a * kVoxelKeyAxisBits + 2)) & kBlockAxisMask; };
    return axis(0) | (axis(1) << kVoxelKeyAxisBits) | (axis(2) << (2 * kVoxelKeyAxisBits));
  }

  /// The value of `key`, or kMissing.
  std::uint32_t find(std::uint64_t key) const {
    const std::uint32_t block = blocks_.find(blockOf(key));
    return block == FlatIndex::kMissing ? kMissing : cells_[cellSlot(block, key)];
  }

  /// The value of `key`, inserting `value` first if the key is new; second: whether it was.
  std::pair<std::uint32_t, bool> tryEmplace(std::uint64_t key, std::uint32_t value) {
    const std::uint64_t block_key = blockOf(key);
    if (block_key != last_block_key_ || cells_.empty()) {
      const auto block = blocks_.tryEmplace(block_key, static_cast<std::uint32_t>(blocks_.size()));
      if (block.second) cells_.resize(cells_.size() + kCellsPerBlock, kMissing);
      last_block_ = block.first;
      last_block_key_ = block_key;
    }
    std::uint32_t& cell = cells_[cellSlot(last_block_, key)];
    if (cell != kMissing) return {cell, false};
    cell = value;
    ++size_;
    return {value, true};
  }

  std::size_t size() const { return size_; }
  std::size_t bytes() const { return blocks_.bytes() + cells_.capacity() * sizeof(std::uint32_t); }

 private:
  /// The cell's place in the block's 64: 2 bits of each axis, x lowest.
  static std::size_t cellSlot(std::uint32_t block, std::uint64_t key) {
    const auto low = [key](int a) { return (key >> (a * kVoxelKeyAxisBits)) & 3u; };
    return std::size_t{block} * kCellsPerBlock + (low(0) | (low(1) << 2) | (low(2) << 4));
  }

  FlatIndex blocks_;                ///< block key -> block number
  std::vector<std::uint32_t> cells_;  ///< kCellsPerBlock values a block, kMissing where none
  std::uint64_t last_block_key_ = 0;  ///< the last tryEmplace()'s block (a surface walk repeats it)
  std::uint32_t last_block_ = 0;
  std::size_t size_ = 0;
};

}  // namespace dynamap
