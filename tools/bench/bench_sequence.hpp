#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"
#include "trajectory_io.hpp"

namespace dynamap::bench {

/// One benchmark frame: colour/depth/mask paths and the ground-truth pose at the colour stamp.
struct BenchFrame {
  std::uint64_t id = 0;
  double timestamp_s = 0.0;
  std::string rgb_path, depth_path, mask_path;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
};

/// Pose at time t from a sorted trajectory: linear translation, slerp rotation; nullopt outside.
std::optional<Eigen::Isometry3d> interpolatePose(const std::vector<TimedPose>& poses, double t);

/// Frames of a TUM sequence with groundtruth.txt and mask/<t>.png (every `every`-th associated
/// frame, at most `max_frames`; frames outside the ground truth are skipped).
std::vector<BenchFrame> loadBenchFrames(const std::string& dir, int every, int max_frames);

struct LoadedFrame {
  cv::Mat bgr, depth_m, dynamic_mask;
};
/// Reads colour, depth (5000 units/m) and the mask (255 = dynamic, anything else static).
LoadedFrame readBenchFrame(const BenchFrame& frame);

}  // namespace dynamap::bench
