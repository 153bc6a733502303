#pragma once

// Fusion tests with a still camera: a tracked point every 10 px of a 640 x 480 image, none
// flagged, and the evidence of a pose (K of freiburg3) with, optionally, each point's id; a
// person in front of a wall whose points shift sideways.

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/dynamic/region_fusion.hpp"

namespace dynamap::test {

inline std::vector<cv::Point2f> pointGrid() {
  std::vector<cv::Point2f> points;
  for (int y = 5; y < 480; y += 10)
    for (int x = 5; x < 640; x += 10) points.emplace_back(float(x), float(y));
  return points;
}

inline FusionEvidence stillCameraEvidence(std::size_t points, bool with_ids) {
  FusionEvidence ev;
  ev.has_pose = true;
  ev.K = cv::Vec4d(535.4, 539.2, 320.1, 247.6);
  if (with_ids)
    for (std::size_t i = 0; i < points; ++i) ev.point_ids.push_back(i);
  return ev;
}

/// A still person's box for keptShare() (his pixels: kStillPerson).
const cv::Rect kStillPerson(280, 120, 90, 260);
const Detection kStillPersonBox{cv::Rect2f(270, 110, 110, 280), 0, 0.9f};

/// Share of `frames` frames in which the person of kStillPersonBox is kept (not masked), given
/// each frame's depth `depth_at(i)`. The camera is still, his tracked points (ids `with_ids`)
/// keep their pixels and are never flagged: a frame-to-frame check sees nothing.
template <typename DepthAt>
double keptShare(const DynamicConfig& c, int frames, DepthAt depth_at, bool with_ids) {
  const std::vector<cv::Point2f> points = pointGrid();
  const std::vector<std::uint8_t> quiet(points.size(), 0);
  const FusionEvidence ev = stillCameraEvidence(points.size(), with_ids);
  RegionFusion fusion(c, ClassTable(c));
  int kept = 0;
  for (int i = 0; i < frames; ++i) {
    const cv::Mat depth = depth_at(i);
    kept += !fusion.fuse(FusionMode::kBoth, depth, points, quiet, {kStillPersonBox}, ev)
                 .objects.at(0)
                 .moving;
  }
  return kept / static_cast<double>(frames);
}

/// A frame with a person 2 m away (kSidewaysPerson) in front of a wall 5 m away: a point every
/// 10 px, those on him shifted `shift` px sideways (and flagged with `flag_person`), ids in `ev`.
const cv::Rect kSidewaysPerson(280, 120, 90, 260);
const Detection kSidewaysPersonBox{cv::Rect2f(260, 110, 130, 280), 0, 0.9f};

struct SidewaysFrame {
  std::vector<cv::Point2f> points;
  std::vector<std::uint8_t> flags;
  cv::Mat depth;
};

inline SidewaysFrame sidewaysFrame(float shift, bool flag_person, FusionEvidence& ev) {
  SidewaysFrame f;
  ev.point_ids.clear();
  for (int y = 5; y < 480; y += 10) {
    for (int x = 5; x < 640; x += 10) {
      const bool on = kSidewaysPerson.contains({x, y});
      f.points.emplace_back(static_cast<float>(x) + (on ? shift : 0.f), static_cast<float>(y));
      f.flags.push_back(on && flag_person ? 1 : 0);
      ev.point_ids.push_back(f.points.size() - 1);
    }
  }
  f.depth = cv::Mat(480, 640, CV_32F, cv::Scalar(5.f));
  f.depth(kSidewaysPerson + cv::Point(cvRound(shift), 0)).setTo(2.f);
  return f;
}

}  // namespace dynamap::test
