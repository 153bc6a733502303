#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/dynamic/depth_check.hpp"

namespace dynamap {

/// A plane n . p_C + d = 0 in the camera frame, |n| = 1.
struct Plane {
  cv::Vec3d n;
  double d = 0.0;
  int inliers = 0;  ///< sampled pixels on it
};

struct SupportPlaneOptions {
  int max_planes = 3;    ///< found one after the other, each from the samples left by the last
  int stride_px = 8;     ///< every stride-th pixel in x and y is sampled
  int iterations = 150;  ///< RANSAC hypotheses per plane
  /// A plane must hold this share of the sampled pixels outside the exclusion (and at least
  /// min_inliers of them): a floor or a wall, not a box face or a jacket.
  double min_share = 0.15;
  int min_inliers = 150;
  /// A point is on a plane within noise_sigmas of the sensor's depth noise at its depth, and
  /// within [min_margin_m, max_margin_m] of it.
  double noise_sigmas = 2.5;
  double min_margin_m = 0.015;
  double max_margin_m = 0.04;
};

/// The large planes of a depth image (intrinsics K = fx, fy, cx, cy) found among the pixels
/// outside `exclude` (CV_8UC1, 255 = not sampled, e.g. the boxes of people; may be empty):
/// the floor, walls, table tops. Deterministic (fixed random seed).
std::vector<Plane> findSupportPlanes(const cv::Mat& depth_m, const cv::Vec4d& K,
                                     const cv::Mat& exclude, const SupportPlaneOptions& options);

/// CV_8UC1 of the depth's size, 255 where a pixel's point lies on one of `planes` (within the
/// margin of SupportPlaneOptions). Nothing standing on a floor or before a wall is on it beyond
/// that margin, so these pixels are no object's own.
cv::Mat planePixels(const cv::Mat& depth_m, const cv::Vec4d& K, const std::vector<Plane>& planes,
                    const SupportPlaneOptions& options);

/// The sampled pixels (check.stride_px, as compareWithView()) of `planes` whose plane `view`
/// (an earlier depth with its pose) saw standing still: projected into the view, each meets there
/// a surface whose point lies on the pixel's own plane within the check's margin. CV_8UC1 of the
/// depth's size, 255 = the sample's stride x stride cell. A floor seen at a grazing angle from
/// another place can look seen through along the rays (a small pose error moves the depth there
/// a lot) while every point the view saw still lies on it; a panel slid along a wall is seen
/// through at its leading edge, where the view saw the wall, far off the panel's plane.
/// `candidates` (CV_8UC1, may be empty = all): only the samples there are judged.
cv::Mat stillPlaneCells(const cv::Mat& depth_m, const cv::Matx44d& T_W_C, const cv::Vec4d& K,
                        const DepthView& view, const std::vector<Plane>& planes,
                        const SupportPlaneOptions& plane_options, const DepthCheckOptions& check,
                        const cv::Mat& candidates = cv::Mat());

}  // namespace dynamap
