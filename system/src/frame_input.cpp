#include "frame_input.hpp"

#include <stdexcept>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace dynamap {
namespace {

std::string sizeText(const cv::Mat& m) {
  return std::to_string(m.cols) + "x" + std::to_string(m.rows);
}

}  // namespace

FrameInput::FrameInput(const PinholeCamera& camera, double depth_scale)
    : depth_scale_(depth_scale) {
  if (!camera.hasDistortion()) return;
  const cv::Matx33d K(camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0);
  cv::Mat D(static_cast<int>(camera.distortion.size()), 1, CV_64F);
  for (int i = 0; i < D.rows; ++i) D.at<double>(i) = camera.distortion[static_cast<std::size_t>(i)];
  cv::initUndistortRectifyMap(K, D, cv::Matx33d::eye(), K, cv::Size(camera.width, camera.height),
                              CV_32FC1, map_x_, map_y_);
}

RgbdFrame FrameInput::prepare(const cv::Mat& bgr, const cv::Mat& depth, double timestamp_s) const {
  if (bgr.empty() || bgr.type() != CV_8UC3) {
    throw std::invalid_argument("colour image must be 8-bit with 3 channels (BGR), got " +
                                std::to_string(bgr.channels()) + " channel(s), depth code " +
                                std::to_string(bgr.depth()));
  }
  if (depth.type() != CV_16UC1 && depth.type() != CV_32FC1) {
    throw std::invalid_argument(
        "depth image must be 16-bit unsigned (units of camera.depth_scale) or 32-bit float "
        "(metres) with 1 channel, got " +
        std::to_string(depth.channels()) + " channel(s), depth code " +
        std::to_string(depth.depth()));
  }
  if (depth.size() != bgr.size()) {
    throw std::invalid_argument("depth image is " + sizeText(depth) + " but colour image is " +
                                sizeText(bgr));
  }
  if (!map_x_.empty() && bgr.size() != map_x_.size()) {
    throw std::invalid_argument("colour image is " + sizeText(bgr) + " but the camera is " +
                                sizeText(map_x_) + " (cannot undistort)");
  }
  RgbdFrame frame;
  frame.timestamp_s = timestamp_s;
  cv::Mat depth_m;
  if (depth.type() == CV_16UC1) {
    depth.convertTo(depth_m, CV_32F, 1.0 / depth_scale_);
  } else {
    depth_m = depth.clone();
  }
  if (map_x_.empty()) {
    frame.bgr = bgr.clone();
    frame.depth_m = depth_m;
  } else {
    cv::remap(bgr, frame.bgr, map_x_, map_y_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    cv::remap(depth_m, frame.depth_m, map_x_, map_y_, cv::INTER_NEAREST, cv::BORDER_CONSTANT);
  }
  return frame;
}

}  // namespace dynamap
