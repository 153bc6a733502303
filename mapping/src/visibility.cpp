#include "dynamap/mapping/visibility.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "dynamap/mapping/flat_index.hpp"
#include "dynamap/mapping/radix_sort.hpp"
#include "in_two.hpp"
#include "plane_fit.hpp"
#include "visibility_votes.hpp"

namespace dynamap {
namespace {

using vis::BesideMover;
using vis::briefUnderMask;
using vis::Element;
using vis::kMinDepthM;

constexpr float kNoReading = 1e9f;

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

constexpr int kAxisBits = 21;
constexpr std::uint64_t kAxisMask = (std::uint64_t{1} << kAxisBits) - 1;

/// 21 bits per axis (voxels of 2 cm: +-20 km); far points wrap, which only merges voxels.
std::uint64_t voxelKey(const Eigen::Vector3f& p, float inv_voxel) {
  const auto k = [inv_voxel](float v) {
    const double cell = std::clamp(std::floor(double(v) * inv_voxel), -1e15, 1e15);
    return static_cast<std::uint64_t>(static_cast<std::int64_t>(cell) + (1 << (kAxisBits - 1))) &
           kAxisMask;
  };
  return k(p.x()) | (k(p.y()) << kAxisBits) | (k(p.z()) << (2 * kAxisBits));
}

/// The key of the voxel (dx, dy, dz) cells away from `key`'s (wrapping as voxelKey() does).
std::uint64_t offsetKey(std::uint64_t key, int dx, int dy, int dz) {
  const int d[3] = {dx, dy, dz};
  std::uint64_t out = 0;
  for (int a = 0; a < 3; ++a) {
    const std::uint64_t cell = (key >> (kAxisBits * a)) + static_cast<std::uint64_t>(d[a]);
    out |= (cell & kAxisMask) << (kAxisBits * a);
  }
  return out;
}

/// A keyframe's static points in runs of consecutive points of one voxel (neighbouring pixels of
/// a row mostly share a 2 cm voxel), the runs sorted by voxel key, then by their first point.
/// ordinal: the run's place in point order; starts[ordinal]: its first point.
struct VoxelRun {
  std::uint64_t key = 0;
  std::uint32_t ordinal = 0;
  std::uint32_t count = 0;
};
struct KeyedPoints {
  std::vector<VoxelRun> runs;
  std::vector<VoxelRun> scratch;  ///< for the sort
  std::vector<std::uint32_t> starts;
  std::vector<Eigen::Vector3f> points;
};

/// A keyframe's runs in point order: each run's element and length. The removal walks the
/// keyframe's static pixels with them instead of keying every point again.
struct RunElements {
  std::vector<std::uint32_t> element;
  std::vector<std::uint32_t> count;
};

/// Runs fn(depth) for every static pixel of a keyframe, in the order forEachStaticPoint() takes.
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

/// Runs fn(depth, u, v, p_W) for every static pixel of a keyframe.
template <typename T, typename Fn>
void forEachStaticPointT(const PinholeCamera& camera, const VisibilityKeyframe& kf, const Fn& fn) {
  const Eigen::Isometry3f pose = kf.T_W_C.cast<float>();
  cv::Mat& depth = *kf.static_depth;
  const auto scale = static_cast<float>(kf.metres_per_unit);
  const auto fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const auto cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  for (int v = 0; v < depth.rows; ++v) {
    T* row = depth.ptr<T>(v);
    const float y_n = (static_cast<float>(v) - cy) / fy;
    for (int u = 0; u < depth.cols; ++u) {
      const float z = static_cast<float>(row[u]) * scale;
      if (!(z > 0.0f)) continue;
      fn(row[u], pose * Eigen::Vector3f((static_cast<float>(u) - cx) / fx * z, y_n * z, z));
    }
  }
}
template <typename Fn>
void forEachStaticPoint(const PinholeCamera& camera, const VisibilityKeyframe& kf, const Fn& fn) {
  if (kf.static_depth->type() == CV_16UC1) {
    forEachStaticPointT<std::uint16_t>(camera, kf, fn);
  } else {
    forEachStaticPointT<float>(camera, kf, fn);
  }
}

enum class Verdict : std::uint8_t { kKept, kRemoved, kBrief };  ///< removedKeys()' first pass
constexpr float kSupportRadiusM = 0.12f;  ///< onConfirmedPlane(): neighbourhood (cube half side)

class ElementTable {
 public:
  explicit ElementTable(double voxel_m) : inv_voxel_(static_cast<float>(1.0 / voxel_m)) {}

  /// A keyframe's points keyed by voxel and sorted. Thread-safe (reads only the voxel size).
  void keyPoints(const PinholeCamera& camera, const VisibilityKeyframe& kf,
                 KeyedPoints& out) const {
    out.runs.clear();
    out.starts.clear();
    out.points.clear();
    forEachStaticPoint(camera, kf, [&](auto&, const Eigen::Vector3f& p_W) {
      const std::uint64_t key = voxelKey(p_W, inv_voxel_);
      const auto index = static_cast<std::uint32_t>(out.points.size());
      out.points.push_back(p_W);
      if (!out.runs.empty() && out.runs.back().key == key) {
        ++out.runs.back().count;
      } else {
        out.runs.push_back({key, static_cast<std::uint32_t>(out.starts.size()), 1});
        out.starts.push_back(index);
      }
    });
    // Made in point order: a stable sort by voxel gives (key, first) order.
    radixSortByKey(out.runs, out.scratch, [](const VoxelRun& r) { return r.key; });
  }

  /// Adds a keyframe's keyed points, point by point in (voxel, point) order: one hash access per
  /// distinct voxel; `out` gets each run's element in point order. Keyframes must be added in the
  /// same order on every run (the element order and the float sums depend on it).
  void add(const KeyedPoints& in, RunElements& out) {
    const auto& runs = in.runs;
    out.element.resize(runs.size());
    out.count.resize(runs.size());
    for (std::size_t b = 0; b < runs.size();) {
      const std::uint64_t key = runs[b].key;
      const auto [i, inserted] =
          index_.tryEmplace(key, static_cast<std::uint32_t>(elements_.size()));
      if (inserted) {
        elements_.emplace_back();
        keys_.push_back(key);
      }
      Element& e = elements_[i];
      for (; b < runs.size() && runs[b].key == key; ++b) {
        const std::uint32_t first = in.starts[runs[b].ordinal];
        for (std::uint32_t p = 0; p < runs[b].count; ++p) e.sum += in.points[first + p];
        e.count += runs[b].count;
        out.element[runs[b].ordinal] = i;
        out.count[runs[b].ordinal] = runs[b].count;
      }
    }
  }

  void computeCentroids() {
    centroids_.resize(elements_.size());
    for (std::size_t i = 0; i < elements_.size(); ++i) {
      centroids_[i] = elements_[i].sum / static_cast<float>(elements_[i].count);
    }
  }

  /// Counts, for the elements [begin, end), whether this view (keyframe `index`) saw through
  /// them. Thread-safe for disjoint ranges.
  void project(const PinholeCamera& camera, const VisibilityView& view,
               const Eigen::Isometry3d& T_W_C, const VisibilityOptions& options, std::size_t begin,
               std::size_t end, std::uint32_t index) {
    const Eigen::Isometry3f T_C_W = T_W_C.inverse().cast<float>();
    const Eigen::Matrix3f R = T_C_W.linear();
    const Eigen::Vector3f t = T_C_W.translation();
    const float s = 1.0f / static_cast<float>(view.downsample);
    const auto fx = static_cast<float>(camera.fx) * s, fy = static_cast<float>(camera.fy) * s;
    const auto cx = static_cast<float>(camera.cx) * s, cy = static_cast<float>(camera.cy) * s;
    const auto margin = static_cast<float>(options.margin_m);
    const auto per_m2 = static_cast<float>(options.margin_per_m2);
    const auto cap = static_cast<std::uint32_t>(std::max(1, options.min_views));
    const int w = view.near_m.cols, h = view.near_m.rows;
    const bool has_mask = view.moving.size() == view.near_m.size();
    for (std::size_t i = begin; i < end; ++i) {
      const Eigen::Vector3f p = R * centroids_[i] + t;
      if (p.z() < kMinDepthM) continue;
      const float uf = fx * p.x() / p.z() + cx, vf = fy * p.y() / p.z() + cy;
      if (!(uf >= 0.0f && vf >= 0.0f && uf < static_cast<float>(w) && vf < static_cast<float>(h)))
        continue;
      const float seen = view.near_m.at<float>(static_cast<int>(vf), static_cast<int>(uf));
      if (seen <= 0.0f) continue;
      const float m = margin + per_m2 * seen * seen;
      Element& e = elements_[i];
      if (e.in_view < 0xffff) ++e.in_view;
      if (p.z() < seen - m) {
        if (e.seen_through < cap) ++e.seen_through;
      } else if (p.z() <= seen + m && e.observed < 0xffff) {
        ++e.observed;
        e.first = std::min(e.first, index);
        e.last = index;  // views come in keyframe order
        if (has_mask && view.moving.at<std::uint8_t>(static_cast<int>(vf), static_cast<int>(uf)))
          ++e.masked;
      }
    }
  }

  /// Per element, 1 if it is removed; counts the removed ones and those removed by mask votes
  /// only. stamps: the keyframes' times (s), in view order.
  std::vector<std::uint8_t> removedElements(const PinholeCamera& camera,
                                            const std::vector<VisibilityKeyframe>& keyframes,
                                            const VisibilityOptions& options,
                                            const std::vector<double>& stamps,
                                            std::size_t* removed, std::size_t* mask_voted) const {
    const BesideMover beside(camera, keyframes, options, stamps);
    std::vector<std::uint8_t> out(elements_.size(), 0);
    std::vector<Verdict> verdicts(elements_.size(), Verdict::kKept);
    std::vector<std::pair<std::uint64_t, std::uint32_t>> brief;
    for (std::uint32_t i = 0; i < elements_.size(); ++i) {
      const Element& e = elements_[i];
      const bool seen_through =
          e.seen_through >= static_cast<std::uint32_t>(std::max(1, options.min_views));
      const bool voted = options.mask_min_views > 0 && e.masked >= options.mask_min_views &&
                         e.masked >= options.mask_ratio * e.observed;
      if (seen_through || voted) {
        verdicts[i] = Verdict::kRemoved;
        out[i] = 1;
        ++*removed;
        if (!seen_through) ++*mask_voted;
      } else if (briefUnderMask(e, options, stamps) || beside.holds(e, centroids_[i])) {
        verdicts[i] = Verdict::kBrief;
        brief.emplace_back(keys_[i], i);
      }
    }
    // The plane test reads only: the candidates in two halves, one per thread.
    std::vector<std::uint8_t> spared(brief.size(), 0);
    inTwo([&](int h) {
      std::vector<Eigen::Vector3f> support;
      const std::size_t half = brief.size() / 2;
      for (std::size_t b = h == 0 ? 0 : half; b < (h == 0 ? half : brief.size()); ++b)
        spared[b] = onConfirmedPlane(brief[b].first, brief[b].second, verdicts, support);
    });
    for (std::size_t b = 0; b < brief.size(); ++b) {
      if (spared[b]) continue;
      out[brief[b].second] = 1;
      ++*removed;
      ++*mask_voted;
    }
    return out;
  }

  /// Whether element i lies on a plane that the kept elements around it (within
  /// kSupportRadiusM, seen by 2 keyframes or more, none of them a brief vote) span: the floor
  /// that a mask took with a foot stays, the foot above it does not. (A flat mover's unmasked
  /// rim can vouch for the rest of it.)
  bool onConfirmedPlane(std::uint64_t key, std::uint32_t i, const std::vector<Verdict>& verdicts,
                        std::vector<Eigen::Vector3f>& support) const {
    const int reach = std::max(1, static_cast<int>(std::lround(kSupportRadiusM * inv_voxel_)));
    support.clear();
    for (int dz = -reach; dz <= reach; ++dz) {
      for (int dy = -reach; dy <= reach; ++dy) {
        for (int dx = -reach; dx <= reach; ++dx) {
          const std::uint32_t j = index_.find(offsetKey(key, dx, dy, dz));
          if (j == FlatIndex::kMissing || j == i) continue;
          if (verdicts[j] == Verdict::kKept && elements_[j].observed >= 2)
            support.push_back(centroids_[j]);
        }
      }
    }
    return liesOnPlane(support, centroids_[i]);
  }
  std::size_t size() const { return elements_.size(); }
  std::size_t bytes() const {
    return elements_.capacity() * sizeof(Element) +
           centroids_.capacity() * sizeof(Eigen::Vector3f) +
           keys_.capacity() * sizeof(std::uint64_t) + index_.bytes();
  }

 private:
  float inv_voxel_;
  FlatIndex index_;
  std::vector<std::uint64_t> keys_;  ///< element i's voxel key
  std::vector<Element> elements_;
  std::vector<Eigen::Vector3f> centroids_;
};

/// Zeroes a keyframe's static pixels whose run's element is removed; returns their number.
std::size_t zeroRemoved(const VisibilityKeyframe& kf, const RunElements& runs,
                        const std::vector<std::uint8_t>& removed) {
  std::size_t run = 0, left = 0, zeroed = 0;
  bool zero = false;
  const auto fn = [&](auto& depth) {
    while (left == 0) {  // the pixels come in point order: the runs cover them one by one
      zero = removed[runs.element[run]] != 0;
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

}  // namespace

VisibilityView makeVisibilityView(const cv::Mat& depth_m, const cv::Mat& dynamic_mask,
                                  const VisibilityOptions& options) {
  VisibilityView view;
  view.downsample = std::max(1, options.downsample);
  if (depth_m.empty()) return view;
  const int f = view.downsample;
  cv::Mat d = depth_m.clone();
  d.setTo(kNoReading, ~(d > 0.0f));
  cv::Mat block(depth_m.rows / f, depth_m.cols / f, CV_32FC1);
  for (int v = 0; v < block.rows; ++v) {
    for (int u = 0; u < block.cols; ++u) {
      double lo = 0.0;
      cv::minMaxLoc(d(cv::Rect(u * f, v * f, f, f)), &lo);
      block.at<float>(v, u) = static_cast<float>(lo);
    }
  }
  cv::erode(block, block, cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
  block.setTo(0.0f, block >= kNoReading);
  view.near_m = block;
  if (dynamic_mask.size() == depth_m.size() && dynamic_mask.type() == CV_8UC1) {
    cv::Mat share;  // block mean of the moving pixels
    cv::resize(cv::Mat(dynamic_mask == 255), share, block.size(), 0, 0, cv::INTER_AREA);
    view.moving = share >= 128;
  }
  return view;
}

VisibilityResult removeSeenThrough(const PinholeCamera& camera,
                                   std::vector<VisibilityKeyframe>& keyframes,
                                   const VisibilityOptions& options) {
  VisibilityResult result;
  const std::size_t n = keyframes.size();
  // Per keyframe and half of the work: CPU ms, summed into per_keyframe_ms at the end.
  std::vector<double> ms[2] = {std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
  ElementTable table(options.voxel_m);
  // Keyframes are keyed two at a time (one per thread) and added in their order.
  KeyedPoints keyed[2];
  std::vector<RunElements> runs(n);  // each keyframe's runs, for the removal
  for (std::size_t i = 0; i < n; i += 2) {
    const auto t_key = Clock::now();
    inTwo([&](int h) {
      const std::size_t k = i + static_cast<std::size_t>(h);
      if (k >= n || keyframes[k].static_depth == nullptr) return;
      const auto t0 = Clock::now();
      table.keyPoints(camera, keyframes[k], keyed[h]);
      ms[h][k] += msSince(t0);
    });
    const auto t_add = Clock::now();
    result.key_ms += msSince(t_key);
    for (int h = 0; h < 2; ++h) {
      const std::size_t k = i + static_cast<std::size_t>(h);
      if (k >= n || keyframes[k].static_depth == nullptr) continue;
      const auto t0 = Clock::now();
      table.add(keyed[h], runs[k]);
      ms[h][k] += msSince(t0);
    }
    result.add_ms += msSince(t_add);
  }
  keyed[0] = keyed[1] = KeyedPoints{};
  auto t_phase = Clock::now();
  table.computeCentroids();
  const std::size_t half = table.size() / 2;
  inTwo([&](int h) {  // each half of the elements against every view
    for (std::size_t j = 0; j < n; ++j) {
      const VisibilityView* view = keyframes[j].view;
      if (view == nullptr || view->near_m.empty()) continue;
      const auto t0 = Clock::now();
      table.project(camera, *view, keyframes[j].T_W_C, options, h == 0 ? 0 : half,
                    h == 0 ? half : table.size(), static_cast<std::uint32_t>(j));
      ms[h][j] += msSince(t0);
    }
  });
  result.project_ms = msSince(t_phase);
  t_phase = Clock::now();
  result.elements = table.size();
  std::vector<double> stamps(n);
  for (std::size_t i = 0; i < n; ++i) stamps[i] = keyframes[i].timestamp_s;
  std::size_t removed_elements = 0;
  const std::vector<std::uint8_t> removed = table.removedElements(
      camera, keyframes, options, stamps, &removed_elements, &result.mask_voted);
  result.seen_through = removed_elements - result.mask_voted;
  result.element_bytes = table.bytes();
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
