#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace dynamap::lk {

/// True where ownPyrLk() computes what OpenCV computes, bit for bit: OpenCV 4.6 on x86-64 (its
/// LK runs the SSE2 path of its baseline build; no other variant is dispatched), a CPU with
/// AVX2, and a 15 px wide window (the only width written here).
bool ownPyrLkUsable(cv::Size window);

/// cv::calcOpticalFlowPyrLK(prev, next, prev_px, next_px, status, cv::noArray(), window,
/// max_level, criteria, cv::OPTFLOW_USE_INITIAL_FLOW) for pyramids that
/// cv::buildOpticalFlowPyramid built with derivatives (minimum eigenvalue threshold 1e-4), with
/// the same results bit for bit: every sum is taken in OpenCV's order (its four float lanes over
/// the first eight pixels of a window row, its scalar sum over the other seven), while the
/// integer work (the bilinear windows, the products) is done for whole rows at once.
/// Check ownPyrLkUsable(window) first.
void ownPyrLk(const std::vector<cv::Mat>& prev, const std::vector<cv::Mat>& next,
              const std::vector<cv::Point2f>& prev_px, std::vector<cv::Point2f>& next_px,
              std::vector<std::uint8_t>& status, cv::Size window, int max_level,
              const cv::TermCriteria& criteria);

}  // namespace dynamap::lk
