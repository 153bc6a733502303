#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace dynamap::lk {

/// True where ownPyrLk() runs: an x86-64 CPU with AVX2 and a 15 px wide window (the only
/// width written here).
bool ownPyrLkUsable(cv::Size window);

/// cv::calcOpticalFlowPyrLK(prev, next, prev_px, next_px, status, cv::noArray(), window,
/// max_level, criteria, cv::OPTFLOW_USE_INITIAL_FLOW) for pyramids that
/// cv::buildOpticalFlowPyramid built with derivatives (minimum eigenvalue threshold 1e-4): the
/// same algorithm (OpenCV's fixed-point bilinear windows, its update and stopping rules), with
/// the integer work of a window done for whole rows at once in AVX2. Tracks agree with
/// OpenCV's within 0.01 px (tests/fast_paths). Check ownPyrLkUsable(window) first.
void ownPyrLk(const std::vector<cv::Mat>& prev, const std::vector<cv::Mat>& next,
              const std::vector<cv::Point2f>& prev_px, std::vector<cv::Point2f>& next_px,
              std::vector<std::uint8_t>& status, cv::Size window, int max_level,
              const cv::TermCriteria& criteria);

}  // namespace dynamap::lk
