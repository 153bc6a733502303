#pragma once

// Internal to RegionFusion (core/src/dynamic/region_fusion.cpp): dynamic points outside the
// detected objects grown into regions, and the pixel helpers fusion shares with them.

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/dynamic/region_fusion.hpp"
#include "dynamap/core/dynamic_config.hpp"

namespace dynamap {

/// True if `p` (rounded) lies on a set pixel of `mask`.
bool insideMask(const cv::Mat& mask, const cv::Point2f& p);

/// `r` grown to whole pixels and clipped to an image of `size`.
cv::Rect clampRect(const cv::Rect2f& r, const cv::Size& size);

/// Removes from `region` (inside `box`) the pixels that are nearer, by more than 4 px, to a
/// proven-static tracked point inside the region than to a dynamic one, and within `radius`
/// of it. Points neither dynamic nor proven static take no part.
void carveStatic(cv::Mat& region, const cv::Rect& box, const std::vector<cv::Point2f>& points,
                 const std::vector<std::uint8_t>& dyn, const std::vector<std::uint8_t>& proven,
                 double radius);

/// Dynamic points outside `claimed` (the detected objects' pixels), grouped by single linkage
/// (cluster_radius_px), each group with enough points and support grown over continuous depth
/// into `mask` (255; the hull of its points without depth). A group whose region the earlier
/// view (evidence.view) saw in place is no mover. Returns the number of groups grown.
int growClusters(const cv::Mat& depth_m, const std::vector<cv::Point2f>& points,
                 const std::vector<std::uint8_t>& dyn, const cv::Mat& claimed,
                 const FusionEvidence& evidence, const DynamicConfig& config, cv::Mat& mask);

}  // namespace dynamap
