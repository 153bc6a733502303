#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/mapping/free_space.hpp"
#include "dynamap/mapping/map_backend.hpp"
#include "dynamap/mapping/visibility.hpp"

namespace dynamap {

struct StaticPointsOptions {
  double depth_min_m = 0.3;
  double depth_max_m = 4.0;
  int mask_dilation_px = 5;  ///< dynamic mask grown by this radius (0 = as is)
  /// MappingWorker: the radius for a backend that fuses its views (MapBackend::fusesViews():
  /// a TSDF's weights, occupancy's log-odds), where a mask rim's few pixels one view let through
  /// are outvoted by the views that saw the space free; a point backend keeps every such point.
  int fused_mask_dilation_px = 3;
  double depth_edge_threshold_m = 0.05;  ///< |depth jump| to a 4-neighbour marking an edge
  int stride = 1;                        ///< pixel step of points_C (static_depth_m is full)
  FreeSpaceOptions free_space;   ///< MappingWorker: drop pixels that violate neighbours' free space
  VisibilityOptions visibility;  ///< MappingWorker: drop what other keyframes saw through
  /// MappingWorker: each keyframe is judged (held revision, then the visibility votes) against
  /// the keyframes within window_before_s (s) before and window_after_s after it, once a keyframe
  /// window_after_s later has arrived (or in drain()), and integrated then.
  double window_before_s = 3.0;
  double window_after_s = 0.7;
  /// Keyframes of the run's first startup_s (s), judged in their window as the others, are
  /// judged again (what later views saw through) once the keyframes startup_window_after_s later
  /// are there, and mapped only then: a mover in view from the first frame (a pushed chair no
  /// detector knows) had no earlier view to be found against, and only views taken after it left
  /// see through its first places. The price: the first second reaches the map that much later.
  /// Off by default (the map within about a second of its frames); config/movers.yaml: 1 s and
  /// 6 s (dev_pushed_chair ghost 1.92 -> 0.09 %, completeness the same). <= 0: none.
  double startup_s = 0.0;
  double startup_window_after_s = 6.0;
  /// Keyframes are judged together once the oldest waiting one is this much older than
  /// window_after_s (their voxels are shared: fewer projections per keyframe).
  double window_batch_s = 0.3;
  /// Views of earlier visits also judge a keyframe: up to this many kept views of keyframes that
  /// left the window, the nearest within 0.5 m and 30 deg of it (a view is kept only where no
  /// kept one lies within 0.1 m and 10 deg: they grow with the space explored). 0 = off.
  int window_revisit_keyframes = 8;
  /// ... and a keyframe's held-back pixels get a second look once the keyframes this long after
  /// it are there (a standing person is often confirmed static only seconds later); what that
  /// unmasks goes to the backend then. <= window_after_s: no second look.
  double held_window_after_s = 3.0;
  /// The offline extra (off by default): the visibility votes and the held revision over all
  /// keyframes in finish(), with the final poses; the backend gets every keyframe only then, so
  /// the map is empty during the run and finish() grows with the run.
  bool visibility_final_pass = false;
  /// MappingWorker (in the window above, or in the final pass): a keyframe's held-back pixels
  /// (KeyframePacket::held_mask) whose world point lies within this voxel's reach of an object
  /// another keyframe confirmed static are unmasked (heldConfirmedElsewhere()). 0 = off.
  double held_revision_voxel_m = 0.03;
  int held_revision_min_keyframes = 2;  ///< other keyframes that confirmed it there
};

/// The static part of one RGB-D keyframe. The only place where masks become map input.
struct StaticPoints {
  cv::Mat static_depth_m;                           ///< CV_32FC1, 0 = dropped
  std::vector<Eigen::Vector3f> points_C;            ///< camera frame
  std::vector<std::array<std::uint8_t, 3>> colors;  ///< RGB, one per point
};

/// The moving pixels of `dynamic_mask` (255) grown by a disc of `radius_px` (0: as they are).
cv::Mat dilatedMask(const cv::Mat& dynamic_mask, int radius_px);

/// depth_m: CV_32FC1 metres (0 = none); bgr: CV_8UC3 or empty (grey points);
/// dynamic_mask: CV_8UC1 with 255 = moving (any other value static), or empty.
/// Drops masked pixels (after dilation), depths outside [min, max], and depth edges (pixels whose
/// depth differs from a valid 4-neighbour by more than the threshold, i.e. mixed pixels).
/// Thread-safe (pure function).
StaticPoints extractStaticPoints(const PinholeCamera& camera, const cv::Mat& bgr,
                                 const cv::Mat& depth_m, const cv::Mat& dynamic_mask,
                                 const StaticPointsOptions& options);

/// The static_depth_m of extractStaticPoints() alone (no points). Thread-safe (pure function).
cv::Mat staticDepth(const cv::Mat& depth_m, const cv::Mat& dynamic_mask,
                    const StaticPointsOptions& options);

/// What a backend's integrate() reads of one keyframe: pointers into `camera`, `bgr` and `sp`,
/// which must outlive the view.
KeyframeView keyframeView(std::uint64_t id, double timestamp_s, const Eigen::Isometry3d& T_W_C,
                          const PinholeCamera& camera, const cv::Mat& bgr, const StaticPoints& sp);

/// Back-projects the non-zero pixels of an already filtered depth image (every `stride`-th pixel).
void backProjectDepth(const PinholeCamera& camera, const cv::Mat& bgr, const cv::Mat& depth_m,
                      int stride, std::vector<Eigen::Vector3f>* points_C,
                      std::vector<std::array<std::uint8_t, 3>>* colors);

}  // namespace dynamap
