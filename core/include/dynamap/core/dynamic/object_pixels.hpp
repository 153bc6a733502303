#pragma once

#include <opencv2/core.hpp>

namespace dynamap {

/// The object's own pixels inside `box`: pixels within `band_m` of the dominant depth mode of
/// the box centre, largest connected component, holes closed. Empty Mat if no depth.
/// Returns a full-image CV_8UC1 mask (255 = object) and the mode in *depth_mode_m. Pixels of
/// `not_object` (CV_8UC1, may be empty) are never the object's; if the box holds depth but only
/// there, the mask is all zero (an empty Mat still means: no depth). With `prior_only` (and a
/// prior) the mask is all zero too when the centre holds depth but none within 0.5 m of the prior:
/// the object is no longer in the box (a carried box at the image border it walked out through),
/// and when the centre holds no depth at all (the sensor's blind band along the border).
/// Depth beyond `max_depth_m` (> 0) is never the object's: where the box holds only such depth,
/// the mask is all zero.
cv::Mat objectPixels(const cv::Mat& depth_m, const cv::Rect& box, double band_m,
                     double* depth_mode_m, double prior_depth_m = 0.0,
                     const cv::Mat& not_object = cv::Mat(), bool prior_only = false,
                     double max_depth_m = 0.0);

}  // namespace dynamap
