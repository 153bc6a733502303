#pragma once

#include <deque>
#include <functional>

#include <opencv2/core.hpp>

namespace dynamap {

/// A past depth frame and the camera pose (camera -> world) it was taken from.
struct DepthView {
  cv::Mat depth_m;  ///< CV_32FC1, 0 = no measurement
  cv::Matx44d T_W_C = cv::Matx44d::eye();
  long frame = -1;     ///< frame number it belongs to
  double scale = 1.0;  ///< its pixels per pixel of the full image (intrinsics scale with it)
};

/// How the pixels of a region agree with what an earlier view saw along the same rays. Each
/// sampled pixel's 3-D point is projected into the view and compared with the view's depth
/// around that pixel (a few pixels of slack for the pose and the edges):
/// consistent: the view saw a surface there within the noise margin (a still surface);
/// seen_through: the view saw beyond the point everywhere around (the point was not there then:
/// something moved in); occluded: the view saw something in front of it (an occluder, or the
/// same surface nearer to the camera then).
struct DepthAgreement {
  int samples = 0;  ///< sampled pixels whose point lies in the view and has depth there
  int consistent = 0;
  int seen_through = 0;
  int occluded = 0;
  double share(int n) const { return samples > 0 ? static_cast<double>(n) / samples : 0.0; }
};

struct DepthCheckOptions {
  int stride_px = 4;            ///< every stride-th pixel in x and y is sampled
  int slack_px = 2;             ///< the view's depth is read in a (2 slack + 1)^2 window
  double noise_sigmas = 3.0;    ///< margin in standard deviations of the difference of 2 depths
  double pose_margin_m = 0.01;  ///< added to the margin for the pose error
  /// ... and this share of the depth, for the sensor's low-frequency depth distortion (a few
  /// centimetres at 3 m towards the image borders on a Kinect).
  double relative_margin = 0.02;
  int border_px = 16;        ///< pixels this close to the image border are not sampled
  double max_depth_m = 0.0;  ///< pixels with a deeper current depth are not sampled (0 = any)
};

/// One standard deviation (m) of a structured-light depth sensor at depth z (m):
/// 0.0012 + 0.0019 (z - 0.4)^2 (Nguyen, Izadi, Lovell 2012, for the Kinect).
inline double depthNoiseM(double z_m) { return 0.0012 + 0.0019 * (z_m - 0.4) * (z_m - 0.4); }

/// How far (m) a view's depth may lie from a point's depth z_m (m) along the same ray and still
/// be the same surface: the noise of two depths, the pose margin and the share of the depth.
double agreementMarginM(double z_m, const DepthCheckOptions& options);

/// The pixel (u, v) of `view` where p_V (a point in the view's camera frame, homogeneous) lands,
/// with the full image's intrinsics K = fx, fy, cx, cy; false if it is behind the view (within
/// 0.1 m) or outside its depth image.
bool viewPixel(const cv::Vec4d& p_V, const cv::Vec4d& K, const DepthView& view, int* u, int* v);

/// Depth at (x, y) unless it has none or a 4-neighbour 4 px away is outside the image, has no
/// depth or differs by more than 0.1 m (a depth edge); else 0. A point on an occlusion edge
/// slides along it as the camera moves and is no fixed point of the surface.
float interiorDepth(const cv::Mat& depth_m, int x, int y);

/// Depth at (x, y) unless, besides interiorDepth()'s test, one of the 8 neighbours `radius_px`
/// away (the corners of the square around it) is outside the image, has no depth or differs by
/// more than `step_m`; else 0. A tracked feature whose window takes in an occluding edge follows
/// that edge, not the surface under it.
float windowInteriorDepth(const cv::Mat& depth_m, int x, int y, int radius_px, float step_m);

/// Compares the sampled pixels of `region` (CV_8UC1, 255 = in; only inside `roi`) of the current
/// depth (pose T_W_C, intrinsics K = fx, fy, cx, cy) with `view`. Pixels on depth edges (a
/// neighbour 4 px away differs by more than 0.1 m) are not sampled. With `seen_through` (a
/// CV_8UC1 image of the depth's size) each seen-through sample sets its stride x stride cell.
DepthAgreement compareWithView(const cv::Mat& depth_m, const cv::Mat& region, const cv::Rect& roi,
                               const cv::Matx44d& T_W_C, const cv::Vec4d& K, const DepthView& view,
                               const DepthCheckOptions& options, cv::Mat* seen_through = nullptr);

struct SeenThroughOptions {
  DepthCheckOptions check;
  int min_region_px = 800;  ///< smaller groups of seen-through pixels are noise
  /// Growth into the whole surface: connected pixels within this of a seed's depth (a fixed
  /// range, not a step: the floor a box stands on joins it smoothly, but leaves the range
  /// within a few rows).
  double depth_range_m = 0.15;
  /// Growth stays inside the group's box grown by this much (m, at the group's depth) on each
  /// side: a seen-through strip is often just the leading edge of what moved.
  double grow_m = 0.5;
  /// Growth does not cross a step in depth between neighbouring pixels larger than this plus
  /// 1 % of the depth (m; 0 = no limit): a chair pushed past the teddy at its depth is one
  /// surface within the fixed range, but the two meet at a step.
  double barrier_step_m = 0.0;
};

/// Pixels of `depth_m` (CV_32FC1, m) next to a neighbour (right, below, or diagonal) whose depth
/// differs by more than step_m + 1 % of the nearer depth, or next to a pixel without depth;
/// CV_8UC1, 1 = a step (both sides of it).
cv::Mat depthSteps(const cv::Mat& depth_m, double step_m);

/// The dense geometric check, which needs no detector: the pixels of the current depth (pose
/// T_W_C) that `view` saw through (it saw a surface behind them, beyond the noise margin: they
/// were not there then), outside `exclude` (CV_8UC1, 255 = already decided; may be empty),
/// in groups of at least min_region_px, each grown into the surface it belongs to (never into
/// `exclude`). A surface that only appeared from behind something (the
/// camera moved) is not seen through: `view` saw the occluder in front of it. CV_8UC1, 255 =
/// moved; *regions = the number of groups kept.
/// `not_seeds` (may be empty): given the seen-through pixels outside `exclude` (CV_8UC1, only
/// called when there are any), returns those that start no group but may be grown into (or an
/// empty Mat).
using SeedFilter = std::function<cv::Mat(const cv::Mat& seeds)>;
cv::Mat seenThroughRegions(const cv::Mat& depth_m, const cv::Matx44d& T_W_C, const cv::Vec4d& K,
                           const DepthView& view, const cv::Mat& exclude,
                           const SeenThroughOptions& options, int* regions = nullptr,
                           const SeedFilter& not_seeds = {});

/// The depth of the last frames with their poses, kept at half resolution, to compare the
/// current frame with an earlier one. Not thread-safe (one caller).
class DepthHistory {
 public:
  /// Keeps frames up to `max_age` frames older than the newest (0: none).
  explicit DepthHistory(int max_age) : max_age_(max_age) {}
  /// A half-resolution copy of `depth_m` as a view (pose to be set before push()).
  static DepthView halfView(const cv::Mat& depth_m, long frame);
  /// Adds a view (newer than every kept one).
  void push(DepthView view);
  /// The newest kept view taken no later than `last_frame`; null if there is none.
  const DepthView* newestUpTo(long last_frame) const;
  void clear() { views_.clear(); }
  /// A frame whose final pose `T_W_final` moved from the pose its check used (`T_W_prior`) by
  /// more than kPoseSnapDeg or kPoseSnapM (the tracker corrected drift at once, e.g. landmarks
  /// found again): every kept view moves with the same correction, so later frames compare with
  /// views in the corrected frame, not across the jump. True if it moved them.
  bool followPoseSnap(const cv::Matx44d& T_W_final, const cv::Matx44d& T_W_prior);
  static constexpr double kPoseSnapDeg = 1.0;
  static constexpr double kPoseSnapM = 0.01;

 private:
  int max_age_;
  std::deque<DepthView> views_;  ///< oldest first
};

}  // namespace dynamap
