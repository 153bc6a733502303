#pragma once

#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"

namespace dynamap {

/// One keyframe for heldConfirmedElsewhere() (MappingWorker::finish()): what its mask held back and what it saw confirmed static.
struct HeldKeyframe {
  cv::Mat depth_m;  ///< CV_32FC1 metres (0 = none)
  cv::Mat held;     ///< CV_8UC1, 255 = masked only for lack of evidence that it stands still
  std::vector<Eigen::Vector3f> confirmed_C;  ///< points of objects confirmed static (camera)
  std::vector<Eigen::Vector3f> moved_C;      ///< points masked for motion (not held; camera)
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
};

/// Points (camera frame) of `mask` (CV_8UC1, 255 = in) with depth, one per `stride_px` square.
std::vector<Eigen::Vector3f> maskPoints(const PinholeCamera& camera, const cv::Mat& depth_m,
                                        const cv::Mat& mask, int stride_px);

/// Evidence gathered over time, used in hindsight: a person held back in one keyframe (masked
/// with no motion of their own, only because they had not yet proven still) whom another
/// keyframe confirmed static at the same place was standing there. For every keyframe, its held
/// pixels whose world point lies within one voxel (`voxel_m`, 26 neighbours included) of points
/// that at least `min_keyframes` other keyframes confirmed static, and more keyframes confirmed
/// static there than saw something move there (a person swaying on the spot is confirmed now
/// and then, but seen moving more often; a walker passing is no standing person). Returns one
/// CV_8UC1 per keyframe (255 = such a pixel), empty where none. Thread-safe (pure function).
std::vector<cv::Mat> heldConfirmedElsewhere(const PinholeCamera& camera,
                                            const std::vector<HeldKeyframe>& keyframes,
                                            double voxel_m, int min_keyframes);

}  // namespace dynamap
