#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"

namespace dynamap {

/// The pixels of a keyframe that a later frame's dynamic mask covers: each keyframe pixel with
/// depth (`depth_m`, pose T_W_K) is projected into the later frame (`later_depth_m`, pose T_W_L);
/// it is marked where the later mask (CV_8UC1, 255 = moving) covers its projection and the later
/// frame saw the same surface there, or one behind it: not an occluder that moved in front of
/// it (nearer by more than `occluder_margin_m`). A person the detector finds a moment after a
/// keyframe (the first frame of a map has no motion evidence at all) was there in the keyframe
/// too, a few pixels away. Nothing is marked when the two poses lie more than 0.3 m or 29 degrees
/// apart (another map's pose after a restart). Returns CV_8UC1 of the keyframe's size, 255 =
/// marked.
cv::Mat maskSeenLater(const PinholeCamera& camera, const cv::Mat& depth_m,
                      const Eigen::Isometry3d& T_W_K, const cv::Mat& later_depth_m,
                      const Eigen::Isometry3d& T_W_L, const cv::Mat& later_mask,
                      double occluder_margin_m = 0.15);

/// A keyframe's final mask without the part of its margin (`radius_px`, the motion filter's
/// dilation) that lies more than `behind_m` behind the depth of the mask's core (the mask eroded
/// by the radius) next to it: the background around a person's outline. Pixels without depth,
/// and those with no core within the radius (a sliver a later frame's mask added), are kept.
/// The map keeps its own margin (StaticPointsOptions::mask_dilation_px). behind_m <= 0: `mask`.
cv::Mat marginNotBehind(const cv::Mat& mask, const cv::Mat& depth_m, int radius_px,
                        double behind_m);

}  // namespace dynamap
