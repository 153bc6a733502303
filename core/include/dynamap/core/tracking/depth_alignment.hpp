#pragma once

#include <optional>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"

namespace dynamap {

/// One depth image with its pose and the pixels that must not take part (movers).
struct PosedDepth {
  cv::Mat depth_m;      ///< CV_32FC1, metres, 0 = no reading
  cv::Mat moving_mask;  ///< CV_8UC1, nonzero = left out; may be empty
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();  ///< of the current one: a guess
};

struct DepthAlignmentOptions {
  double min_depth_m = 0.3;
  double max_depth_m = 4.0;
  /// OpenCV's ICP runs twice: associations up to this far apart (reaching the minimum from the
  /// guess), then from its result ...
  double coarse_depth_difference_m = 0.3;
  double fine_depth_difference_m = 0.07;  ///< ... up to this far (robust to what it left out)
  double max_translation_m = 0.15;        ///< OpenCV's ICP fails beyond this step
  double max_rotation_deg = 15.0;         ///< ... or this one
  // The score of the result (accepted or not):
  int pixel_stride = 4;           ///< every n-th pixel of every n-th row of the current image
  double end_gate_m = 0.03;       ///< association distance
  double huber_m = 0.01;          ///< residuals beyond weigh less
  double inlier_m = 0.015;        ///< |point-to-plane residual| of an inlier at the end
  int min_inliers = 1500;         ///< fewer: not accepted
  double min_inlier_share = 0.5;  ///< of the associated points at the end
  /// How many points (normals along it) pin down the weakest translation direction: the
  /// smallest eigenvalue of the normal equations' translation block, sum of w n n^T. Fewer,
  /// and the surfaces leave a translation free (one plane, a corridor): not accepted. With
  /// 1 cm depth noise, 100 such points fix that direction to about 1 mm.
  double min_weakest_direction_points = 100.0;
};

/// The outcome of a depth alignment, accepted or not (why not: `accepted` false).
struct DepthAlignment {
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  int inliers = 0;
  double inlier_share = 0.0;
  double rms_m = 0.0;                     ///< point-to-plane, over the inliers
  double weakest_direction_points = 0.0;  ///< see DepthAlignmentOptions
  bool accepted = false;
};

/// `current`'s static pixels aligned to `reference`'s static surface by OpenCV's point-to-plane
/// ICP odometry (cv::rgbd::ICPOdometry, a depth pyramid), starting at `current.T_W_C`; the
/// result is then scored with projective association (each current point meets the reference
/// pixel it projects to, whose normal comes from its neighbours). The dense term where features
/// are few (a view filled by people): it needs only depth, and rejects alignments the geometry
/// does not pin down.
DepthAlignment alignDepth(const PosedDepth& reference, const PosedDepth& current,
                          const PinholeCamera& camera, const DepthAlignmentOptions& options = {});

}  // namespace dynamap
