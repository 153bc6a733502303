#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/dynamic/class_table.hpp"
#include "dynamap/core/dynamic/depth_check.hpp"
#include "dynamap/core/dynamic/nms.hpp"
#include "dynamap/core/dynamic/region_fusion.hpp"

namespace dynamap {

/// Movers no detector knows (a pushed box, chair or cart): the regions of the current depth that
/// an earlier view saw through (seenThroughRegions(): something moved in since), outside
/// `exclude` (CV_8UC1, may be empty: objects decided static, people the detector boxes, the
/// support planes), one detection of class ClassTable::kMover per connected region. Fusion
/// tracks them as it tracks a detector's objects: masked until they have shown that they stand
/// still, carried by the flow when geometry misses them for a frame or two. `T_W_C` is the
/// current pose (camera -> world), K = fx, fy, cx, cy. *regions (optional): how many. A region
/// within 15 px of `walkers` (CV_8UC1, may be empty: the own pixels of the people who moved) is
/// no mover: it is a walker's (an arm or leg off his body's depth), which his track and the
/// frame's dense check mask; tracked as a mover it outlived him over the little static
/// background a crowd leaves (the Bonn slice backward from frame 10: 5 lost frames).
std::vector<Detection> moverDetections(const cv::Mat& depth_m, const cv::Matx44d& T_W_C,
                                       const cv::Vec4d& K, const DepthView& view,
                                       const cv::Mat& exclude, const SeenThroughOptions& options,
                                       int* regions = nullptr, const cv::Mat& walkers = cv::Mat());

/// Where no mover is looked for (CV_8UC1 of depth_m's size, 255 = not): the movers fusion kept
/// last frame (`kept_movers`, keptMovers(); a box that stopped), the support planes (`planes`,
/// may be empty) and the people of the high-dynamic detections (their own tracks judge them):
/// in each box the pixels within `band_m` of its depth mode (objectPixels()) and 5 px around
/// them, all of the box where it holds no depth. What moves behind a person's box is looked at:
/// teddy_dyn_dev's teddy, taken for a person, has a box over half the view, and a walker behind
/// it was a mover only outside that box (12 starts, config/movers.yaml: keyframe-mask IoU .725
/// with whole boxes, .760 with own pixels, .764 without mover tracks). A chair the detector
/// knows is looked at: its class says it does not move by itself, not that nobody pushes it.
cv::Mat notMovers(const cv::Mat& depth_m, const cv::Mat& kept_movers, const cv::Mat& planes,
                  const std::vector<Detection>& detections, const ClassTable& classes,
                  double band_m);

/// The own pixels of the high-dynamic detections (as notMovers() takes them, without margin;
/// nothing for a box without depth): CV_8UC1 of depth_m's size.
cv::Mat peoplePixels(const cv::Mat& depth_m, const std::vector<Detection>& detections,
                     const ClassTable& classes, double band_m);

/// The pixels of the movers (ClassTable::kMover) that `fused` decided static.
cv::Mat keptMovers(const FusionResult& fused);

}  // namespace dynamap
