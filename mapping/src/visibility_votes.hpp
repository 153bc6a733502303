#pragma once
// The visibility pass's map elements and its vote rules for movers that no keyframe saw through
// (seenBriefly(), briefUnderMask(), BesideMover). Internal to dynamap_mapping
// (mapping/src/visibility.cpp).
#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/mapping/visibility.hpp"

namespace dynamap::vis {

constexpr double kMinDepthM = 0.1;  // elements nearer to a camera than this are not checked

/// A voxel of the map (options.voxel_m): the sums for the centroid of the static points in it,
/// and what the views said of it.
struct Element {
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  std::uint32_t count = 0;
  std::uint32_t seen_through = 0;
  std::uint16_t observed = 0;  ///< keyframes whose surface at the projection is this element
  std::uint16_t masked = 0;    ///< of those, under the keyframe's dynamic mask
  std::uint16_t in_view = 0;   ///< keyframes with a depth reading at its projection
  std::uint32_t first = std::numeric_limits<std::uint32_t>::max();  ///< first observing keyframe
  std::uint32_t last = 0;                                           ///< last observing keyframe
};

/// What both vote rules below ask of an element: some keyframe saw it, every keyframe that saw
/// it did so within options.mask_span_s, and at least mask_span_view_ratio times as many had it
/// in view (something else in front, or the surface behind it within the margin).
inline bool seenBriefly(const Element& e, const VisibilityOptions& options,
                        const std::vector<double>& stamps, double view_ratio) {
  if (options.mask_span_s <= 0.0 || e.observed == 0 || e.last >= stamps.size()) return false;
  return stamps[e.last] - stamps[e.first] <= options.mask_span_s &&
         e.in_view >= view_ratio * e.observed;
}
inline bool seenBriefly(const Element& e, const VisibilityOptions& options,
                        const std::vector<double>& stamps) {
  return seenBriefly(e, options, stamps, options.mask_span_view_ratio);
}

/// A mover that stood still for a moment (a foot during a step): seen briefly, and by some
/// keyframe under its mask.
inline bool briefUnderMask(const Element& e, const VisibilityOptions& options,
                           const std::vector<double>& stamps) {
  return e.masked != 0 && seenBriefly(e, options, stamps);
}

/// The beside-a-mover rule (options.mask_near_px, mask_near_depth_m): an element that a single
/// keyframe (up to options.mask_near_max_views) saw, unmasked, seen briefly, and that a keyframe
/// within options.mask_span_s saw with moving blocks near its projection and near its depth; or,
/// where those blocks are a moved object's (not a person's), one seen briefly by
/// mask_near_object_view_ratio that up to options.mask_near_object_max_views saw unmasked or
/// some keyframe saw under its mask (the brief rule's case, with that ratio).
class BesideMover {
 public:
  BesideMover(const PinholeCamera& camera, const std::vector<VisibilityKeyframe>& keyframes,
              const VisibilityOptions& options, const std::vector<double>& stamps)
      : camera_(camera), keyframes_(keyframes), options_(options), stamps_(stamps) {
    if (options.mask_near_px <= 0 || options.mask_span_s <= 0.0) return;
    T_C_W_.reserve(keyframes.size());
    for (const auto& kf : keyframes) T_C_W_.push_back(kf.T_W_C.inverse().cast<float>());
  }

  bool holds(const Element& e, const Eigen::Vector3f& centroid) const {
    if (T_C_W_.empty()) return false;
    if (e.masked == 0 && e.observed <= options_.mask_near_max_views &&
        seenBriefly(e, options_, stamps_) && moverNear(e, centroid, &VisibilityView::moving))
      return true;
    const int object_views = options_.mask_near_object_max_views;
    return object_views > 0 && (e.masked != 0 || e.observed <= object_views) &&
           seenBriefly(e, options_, stamps_, options_.mask_near_object_view_ratio) &&
           moverNear(e, centroid, &VisibilityView::moved_objects);
  }

 private:
  using Blocks = cv::Mat VisibilityView::*;

  /// A keyframe within mask_span_s of the first that saw e has `blocks` beside it.
  bool moverNear(const Element& e, const Eigen::Vector3f& centroid, Blocks blocks) const {
    const double t = stamps_[e.first];
    std::size_t j = e.first;
    while (j > 0 && t - stamps_[j - 1] <= options_.mask_span_s) --j;
    for (; j < stamps_.size() && stamps_[j] - t <= options_.mask_span_s; ++j) {
      if (moverBeside(j, centroid, blocks)) return true;
    }
    return false;
  }

  bool moverBeside(std::size_t j, const Eigen::Vector3f& centroid, Blocks blocks) const {
    const VisibilityView* view = keyframes_[j].view;
    if (view == nullptr || (view->*blocks).size() != view->near_m.size()) return false;
    const Eigen::Vector3f p = T_C_W_[j] * centroid;
    if (p.z() < kMinDepthM) return false;
    const double s = 1.0 / view->downsample;
    const double u = (camera_.fx * p.x() / p.z() + camera_.cx) * s;
    const double v = (camera_.fy * p.y() / p.z() + camera_.cy) * s;
    const cv::Mat& near = view->near_m;
    if (!(u >= 0.0 && v >= 0.0 && u < near.cols && v < near.rows)) return false;
    const auto hi =
        static_cast<float>(p.z() + options_.margin_m + options_.margin_per_m2 * p.z() * p.z());
    const auto lo = static_cast<float>(p.z() - options_.mask_near_depth_m);
    const int reach = options_.mask_near_px / view->downsample;
    const int u0 = static_cast<int>(u), v0 = static_cast<int>(v);
    for (int y = std::max(0, v0 - reach); y <= std::min(near.rows - 1, v0 + reach); ++y) {
      const float* depth = near.ptr<float>(y);
      const std::uint8_t* moving = (view->*blocks).ptr<std::uint8_t>(y);
      for (int x = std::max(0, u0 - reach); x <= std::min(near.cols - 1, u0 + reach); ++x) {
        if (moving[x] != 0 && depth[x] > 0.0f && depth[x] >= lo && depth[x] <= hi) return true;
      }
    }
    return false;
  }

  const PinholeCamera& camera_;
  const std::vector<VisibilityKeyframe>& keyframes_;
  const VisibilityOptions& options_;
  const std::vector<double>& stamps_;
  std::vector<Eigen::Isometry3f> T_C_W_;
};

}  // namespace dynamap::vis
