#include "dynamap/mapping/visibility.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "dynamap/mapping/in_two.hpp"
#include "dynamap/mapping/radix_sort.hpp"
#include "dynamap/mapping/static_points.hpp"
#include "visibility_table.hpp"

namespace dynamap {
namespace {

using vis::BesideMover;
using vis::KeyedPoints;
using vis::RunElements;
using vis::SplitTable;
using vis::Verdict;
using vis::VoxelRun;

constexpr float kNoReading = 1e9f;

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// Runs fn(depth) for every static pixel of a keyframe, in the order keyPoints() takes.
template <typename T, typename Fn>
void forEachStaticPixelT(const VisibilityKeyframe& kf, const Fn& fn) {
  cv::Mat& depth = *kf.static_depth;
  const auto scale = static_cast<float>(kf.metres_per_unit);
  for (int v = 0; v < depth.rows; ++v) {
    T* row = depth.ptr<T>(v);
    for (int u = 0; u < depth.cols; ++u) {
      if (static_cast<float>(row[u]) * scale > 0.0f) fn(row[u]);
    }
  }
}

/// A keyframe's points keyed by voxel and sorted. Row by row: first the points and keys of the
/// row's static pixels (independent of each other), then the runs of equal keys. Thread-safe.
template <typename T>
void keyPointsT(const PinholeCamera& camera, const VisibilityKeyframe& kf, float inv_voxel,
                KeyedPoints& out) {
  const Eigen::Isometry3f pose = kf.T_W_C.cast<float>();
  const cv::Mat& depth = *kf.static_depth;
  const auto scale = static_cast<float>(kf.metres_per_unit);
  const auto fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const auto cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  out.points.resize(depth.total());  // at most one point a pixel; cut to size below
  out.keys.resize(static_cast<std::size_t>(depth.cols));
  Eigen::Vector3f* points = out.points.data();
  std::uint64_t* keys = out.keys.data();
  std::size_t n = 0;
  for (int v = 0; v < depth.rows; ++v) {
    const T* row = depth.ptr<T>(v);
    const float y_n = (static_cast<float>(v) - cy) / fy;
    std::size_t m = 0;
    for (int u = 0; u < depth.cols; ++u) {
      const float z = static_cast<float>(row[u]) * scale;
      if (!(z > 0.0f)) continue;
      const Eigen::Vector3f p_W =
          pose * Eigen::Vector3f((static_cast<float>(u) - cx) / fx * z, y_n * z, z);
      points[n + m] = p_W;
      keys[m++] = vis::voxelKey(p_W, inv_voxel);
    }
    for (std::size_t i = 0; i < m; ++i) {
      if (!out.runs.empty() && out.runs.back().key == keys[i]) {
        ++out.runs.back().count;
      } else {
        out.runs.push_back({keys[i], static_cast<std::uint32_t>(out.starts.size()), 1});
        out.starts.push_back(static_cast<std::uint32_t>(n + i));
      }
    }
    n += m;
  }
  out.points.resize(n);
}

/// A keyframe's points keyed by voxel, the runs sorted by (key, first point). Thread-safe.
void keyPoints(const PinholeCamera& camera, const VisibilityKeyframe& kf, float inv_voxel,
               KeyedPoints& out) {
  out.runs.clear();
  out.starts.clear();
  out.points.clear();
  if (kf.static_depth->type() == CV_16UC1) {
    keyPointsT<std::uint16_t>(camera, kf, inv_voxel, out);
  } else {
    keyPointsT<float>(camera, kf, inv_voxel, out);
  }
  // Made in point order: a stable sort by voxel gives (key, first) order.
  radixSortByKey(out.runs, out.scratch, [](const VoxelRun& r) { return r.key; });
}

/// Keys the keyframes a few at a time (the two threads take them as they come) and adds them in
/// their order, each thread to its part of the table. ms: CPU ms per thread and keyframe.
void fillTable(const PinholeCamera& camera, const std::vector<VisibilityKeyframe>& keyframes,
               float inv_voxel, SplitTable& table, std::vector<RunElements>& runs,
               std::vector<double> (&ms)[2], VisibilityResult& result) {
  constexpr std::size_t kBatch = 4;
  const std::size_t n = keyframes.size();
  std::array<KeyedPoints, kBatch> keyed;
  for (std::size_t b0 = 0; b0 < n; b0 += kBatch) {
    const std::size_t b1 = std::min(n, b0 + kBatch);
    auto t_phase = Clock::now();
    std::atomic<std::size_t> next{b0};
    inTwo([&](int h) {
      for (std::size_t k = next++; k < b1; k = next++) {
        if (keyframes[k].static_depth == nullptr) continue;
        const auto t0 = Clock::now();
        keyPoints(camera, keyframes[k], inv_voxel, keyed[k - b0]);
        ms[h][k] += msSince(t0);
      }
    });
    result.key_ms += msSince(t_phase);
    t_phase = Clock::now();
    for (std::size_t k = b0; k < b1; ++k) {
      if (keyframes[k].static_depth == nullptr) continue;
      runs[k].element.resize(keyed[k - b0].runs.size());
      runs[k].count.resize(keyed[k - b0].runs.size());
    }
    inTwo([&](int h) {
      for (std::size_t k = b0; k < b1; ++k) {
        if (keyframes[k].static_depth == nullptr) continue;
        const auto t0 = Clock::now();
        table[h].add(keyed[k - b0], runs[k]);
        ms[h][k] += msSince(t0);
      }
    });
    result.add_ms += msSince(t_phase);
  }
}

/// Per part and element, 1 if it is removed; counts the removed ones and those removed by mask
/// votes only. stamps: the keyframes' times (s), in view order.
std::array<std::vector<std::uint8_t>, 2> removedElements(
    const PinholeCamera& camera, const std::vector<VisibilityKeyframe>& keyframes,
    const VisibilityOptions& options, const std::vector<double>& stamps, float inv_voxel,
    SplitTable& table, std::size_t* removed, std::size_t* mask_voted) {
  const BesideMover beside(camera, keyframes, options, stamps);
  std::array<std::vector<std::uint32_t>, 2> brief;
  std::size_t counts[2][2] = {{0, 0}, {0, 0}};
  inTwo([&](int h) {
    table[h].judge(options, stamps, beside, &brief[h], &counts[h][0], &counts[h][1]);
  });
  // The plane test reads only: each thread its part's candidates.
  std::array<std::vector<std::uint8_t>, 2> spared;
  inTwo([&](int h) {
    std::vector<Eigen::Vector3f> support;
    spared[h].resize(brief[h].size());
    for (std::size_t b = 0; b < brief[h].size(); ++b)
      spared[h][b] = onConfirmedPlane(table, h, brief[h][b], inv_voxel, support);
  });
  std::array<std::vector<std::uint8_t>, 2> out;
  for (int h = 0; h < 2; ++h) {
    *removed += counts[h][0];
    *mask_voted += counts[h][1];
    out[h].assign(table[h].size(), 0);
    for (std::uint32_t i = 0; i < table[h].size(); ++i)
      out[h][i] = table[h].verdict(i) == Verdict::kRemoved;
    for (std::size_t b = 0; b < brief[h].size(); ++b) {
      if (spared[h][b]) continue;
      out[h][brief[h][b]] = 1;
      ++*removed;
      ++*mask_voted;
    }
  }
  return out;
}

/// Zeroes a keyframe's static pixels whose run's element is removed; returns their number.
std::size_t zeroRemoved(const VisibilityKeyframe& kf, const RunElements& runs,
                        const std::array<std::vector<std::uint8_t>, 2>& removed) {
  std::size_t run = 0, left = 0, zeroed = 0;
  bool zero = false;
  const auto fn = [&](auto& depth) {
    while (left == 0) {  // the pixels come in point order: the runs cover them one by one
      const std::uint32_t e = runs.element[run];
      zero = removed[e & 1u][e >> 1] != 0;
      left = runs.count[run++];
    }
    --left;
    if (zero) {
      depth = 0;
      ++zeroed;
    }
  };
  if (kf.static_depth->type() == CV_16UC1) {
    forEachStaticPixelT<std::uint16_t>(kf, fn);
  } else {
    forEachStaticPixelT<float>(kf, fn);
  }
  return zeroed;
}

/// 255 where at least half of a block of `mask` (grown by grow_px) is set; empty without a
/// mask of the image's size.
cv::Mat movingBlocks(const cv::Mat& mask, const cv::Size& image, const cv::Size& blocks,
                     int grow_px) {
  if (mask.size() != image || mask.type() != CV_8UC1) return {};
  cv::Mat share;  // block mean of the moving pixels
  cv::resize(dilatedMask(mask, grow_px), share, blocks, 0, 0, cv::INTER_AREA);
  return share >= 128;
}

}  // namespace

VisibilityView makeVisibilityView(const cv::Mat& depth_m, const cv::Mat& dynamic_mask,
                                  const VisibilityOptions& options,
                                  const cv::Mat& moved_object_mask) {
  VisibilityView view;
  view.downsample = std::max(1, options.downsample);
  if (depth_m.empty()) return view;
  const int f = view.downsample;
  cv::Mat d = depth_m.clone();
  d.setTo(kNoReading, ~(d > 0.0f));
  cv::Mat block(depth_m.rows / f, depth_m.cols / f, CV_32FC1);  // each f x f block's minimum
  for (int v = 0; v < block.rows; ++v) {
    float* out = block.ptr<float>(v);
    for (int u = 0; u < block.cols; ++u) out[u] = d.at<float>(v * f, u * f);
    for (int y = v * f; y < (v + 1) * f; ++y) {
      const float* row = d.ptr<float>(y);
      for (int u = 0; u < block.cols; ++u) {
        for (int x = u * f; x < (u + 1) * f; ++x) out[u] = std::min(out[u], row[x]);
      }
    }
  }
  cv::erode(block, block, cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
  block.setTo(0.0f, block >= kNoReading);
  view.near_m = block;
  view.moving = movingBlocks(dynamic_mask, depth_m.size(), block.size(), options.mask_grow_px);
  view.moved_objects =
      movingBlocks(moved_object_mask, depth_m.size(), block.size(), options.mask_grow_px);
  return view;
}

VisibilityResult removeSeenThrough(const PinholeCamera& camera,
                                   std::vector<VisibilityKeyframe>& keyframes,
                                   const VisibilityOptions& options) {
  VisibilityResult result;
  const std::size_t n = keyframes.size();
  // Per keyframe and half of the work: CPU ms, summed into per_keyframe_ms at the end.
  std::vector<double> ms[2] = {std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
  const auto inv_voxel = static_cast<float>(1.0 / options.voxel_m);
  SplitTable table{vis::ElementTable(0), vis::ElementTable(1)};
  std::vector<RunElements> runs(n);  // each keyframe's runs, for the removal
  fillTable(camera, keyframes, inv_voxel, table, runs, ms, result);
  auto t_phase = Clock::now();
  inTwo([&](int h) {  // each part of the table against every view
    table[h].computeCentroids();
    for (std::size_t j = 0; j < n; ++j) {
      const VisibilityView* view = keyframes[j].view;
      if (view == nullptr || view->near_m.empty()) continue;
      const auto t0 = Clock::now();
      table[h].project(camera, *view, keyframes[j].T_W_C, options, static_cast<std::uint32_t>(j));
      ms[h][j] += msSince(t0);
    }
  });
  result.project_ms = msSince(t_phase);
  t_phase = Clock::now();
  result.elements = table[0].size() + table[1].size();
  std::vector<double> stamps(n);
  for (std::size_t i = 0; i < n; ++i) stamps[i] = keyframes[i].timestamp_s;
  std::size_t removed_elements = 0;
  const auto removed = removedElements(camera, keyframes, options, stamps, inv_voxel, table,
                                       &removed_elements, &result.mask_voted);
  result.seen_through = removed_elements - result.mask_voted;
  result.element_bytes = table[0].bytes() + table[1].bytes();
  result.verdict_ms = msSince(t_phase);
  t_phase = Clock::now();
  if (removed_elements > 0) {
    std::size_t removed_pixels[2] = {0, 0};
    inTwo([&](int h) {  // every other keyframe: each thread writes only its keyframes' depth
      for (std::size_t i = static_cast<std::size_t>(h); i < n; i += 2) {
        if (keyframes[i].static_depth == nullptr) continue;
        const auto t0 = Clock::now();
        removed_pixels[h] += zeroRemoved(keyframes[i], runs[i], removed);
        ms[h][i] += msSince(t0);
      }
    });
    result.removed_pixels = removed_pixels[0] + removed_pixels[1];
  }
  result.zero_ms = msSince(t_phase);
  result.per_keyframe_ms.resize(n);
  for (std::size_t i = 0; i < n; ++i) result.per_keyframe_ms[i] = ms[0][i] + ms[1][i];
  return result;
}

}  // namespace dynamap
