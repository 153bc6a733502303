#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"

namespace dynamap {

struct VisibilityOptions {
  bool enabled = true;
  double voxel_m = 0.02;        ///< map elements: centroids of the static points per voxel
  int min_views = 1;            ///< keyframes that must have seen through an element
  int downsample = 4;           ///< depth views are kept at 1/downsample resolution
  double margin_m = 0.06;       ///< an element must lie this far in front of what a view saw...
  double margin_per_m2 = 0.02;  ///< ... plus this times depth^2 (sensor noise grows with z^2)
  /// Mask votes (0 = off): an element that at least this many keyframes saw (their surface at
  /// its projection within the margin) under their dynamic mask, and at least mask_ratio of
  /// all the keyframes that saw it, is a mover one keyframe's mask missed.
  int mask_min_views = 2;
  double mask_ratio = 0.5;
  /// Brief mask votes (0 = off): an element that one keyframe saw under its mask, that every
  /// keyframe seeing it saw within mask_span_s (s), and that at least mask_span_view_ratio
  /// times as many keyframes had in view, is a mover that stood still for a moment.
  double mask_span_s = 0.7;
  double mask_span_view_ratio = 2.0;
  /// Beside a mover (0 = off): an element that a single keyframe saw, unmasked, and that at
  /// least mask_span_view_ratio times as many keyframes had in view, is a mover's part that every
  /// mask missed when a keyframe within mask_span_s had moving pixels within mask_near_px pixels
  /// of its projection at a depth from mask_near_depth_m in front of it to the margin behind it
  /// (a leg showing beside a box before anything detected the person; not a passer-by far in
  /// front). Voxels of this rule and the brief one stay when they lie on the plane of the kept
  /// voxels around them.
  int mask_near_px = 24;
  double mask_near_depth_m = 0.3;
  /// The rule's "a single keyframe": up to this many (a mover seen by the first keyframes of a
  /// run before anything found it moving, and hidden behind itself afterwards).
  int mask_near_max_views = 1;
  /// Beside a moved object that is not a person (VisibilityView::moved_objects: a pushed chair,
  /// a cart), the rule takes surfaces up to this many keyframes saw unmasked, and any that a
  /// keyframe saw under its mask, seen briefly by mask_near_object_view_ratio instead of
  /// mask_span_view_ratio: an object moving from the run's first frame, or into the view, leaves
  /// its first places in the keyframes before anything found it, and is itself in front of them
  /// afterwards, so no view sees them empty (0 = off: the rules as above).
  int mask_near_object_max_views = 3;
  double mask_near_object_view_ratio = 1.0;
  /// The dynamic mask is grown by this radius (px) before its blocks are judged: the margin
  /// that a keyframe's mask keeps off the background (mapping.mask_margin_behind_m) still
  /// counts for the votes of what lies at a mover's outline.
  int mask_grow_px = 3;
};

/// What one keyframe saw, kept for the whole run: the nearest surface of its full depth image
/// (movers included) in a window of 3 x `downsample` pixels, at 1/downsample resolution (a
/// 160 x 120 float image for 640 x 480 and downsample 4: 77 KB). The window makes depth edges
/// and small pose errors count as "not seen through".
struct VisibilityView {
  cv::Mat near_m;         ///< CV_32FC1, 0 = no reading in the window
  cv::Mat moving;         ///< CV_8UC1, 255 = at least half the block under the mask; may be empty
  cv::Mat moved_objects;  ///< the same of moved objects that are not people; may be empty
  int downsample = 1;
};

/// dynamic_mask: CV_8UC1, 255 = moving (as extractStaticPoints()), or empty; moved_object_mask
/// its part on moving objects that are not people (KeyframePacket::moved_object_mask), or empty.
VisibilityView makeVisibilityView(const cv::Mat& depth_m, const cv::Mat& dynamic_mask,
                                  const VisibilityOptions& options,
                                  const cv::Mat& moved_object_mask = cv::Mat());

/// One keyframe for the visibility pass: its static depth (what goes into the map; removed
/// pixels are set to 0 in place), its final pose and its view.
struct VisibilityKeyframe {
  cv::Mat* static_depth = nullptr;  ///< CV_32FC1 or CV_16UC1, 0 = not in the map
  double metres_per_unit = 1.0;     ///< depth scale (1 for metres, 1/5000 for TUM 16-bit)
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  const VisibilityView* view = nullptr;
  double timestamp_s = 0.0;  ///< keyframes come in time order
};

struct VisibilityResult {
  std::size_t elements = 0;      ///< voxels of the map checked
  std::size_t seen_through = 0;  ///< of those, removed because some keyframe saw through them
  std::size_t mask_voted = 0;    ///< removed by mask votes (plain or brief) only
  std::size_t removed_pixels = 0;
  std::size_t element_bytes = 0;        ///< memory of the element table during the pass
  std::vector<double> per_keyframe_ms;  ///< cost of each keyframe (build + projection + removal)
  /// Wall time (ms) of the pass's phases: keying the keyframes' static points into voxels,
  /// adding them to the element table, projecting the elements into the views, the verdicts,
  /// zeroing the removed pixels.
  double key_ms = 0.0, add_ms = 0.0, project_ms = 0.0, verdict_ms = 0.0, zero_ms = 0.0;
};

/// Visibility over all keyframes with their final poses (in the spirit of Removert / ERASOR):
/// the static points of every keyframe are gathered into voxels (centroids), every voxel is
/// projected into every keyframe's view, and a voxel that at least `min_views` keyframes saw
/// through (the view's surface at its projection lies behind it by more than margin_m +
/// margin_per_m2 * z^2) was not there at that time: its pixels are set to 0 in every
/// keyframe's static depth. So is a voxel that most keyframes seeing it saw under their
/// dynamic mask (options.mask_min_views, mask_ratio), one that a keyframe saw under its mask
/// and all keyframes saw only within a short time (options.mask_span_s, mask_span_view_ratio;
/// keyframes must come in time order), and one that a single keyframe (up to
/// mask_near_object_max_views beside a moved object) saw beside a mover (options.mask_near_px).
/// Anything that every visit saw (a
/// standing person, the teddy) stays. Cost: one projection of the voxel centroids per keyframe, no
/// point pairs. Runs on two threads (keyframes keyed four at a time, whichever thread is free,
/// and added in their order; the element table in two parts by the parity of the voxel key,
/// each filled, projected and judged by one thread; removal split by keyframe, walking each
/// keyframe's runs of one voxel as keyed): the result does not depend on the threads.
/// per_keyframe_ms is CPU time. Thread-safe for distinct keyframes (modifies only their depth
/// images).
VisibilityResult removeSeenThrough(const PinholeCamera& camera,
                                   std::vector<VisibilityKeyframe>& keyframes,
                                   const VisibilityOptions& options);

}  // namespace dynamap
