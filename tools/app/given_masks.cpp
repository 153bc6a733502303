#include "given_masks.hpp"

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace dynamap {

std::string maskPathFor(const std::string& masks_dir, const std::string& rgb_path,
                        double timestamp_s) {
  namespace fs = std::filesystem;
  const fs::path by_stem = fs::path(masks_dir) / (fs::path(rgb_path).stem().string() + ".png");
  if (fs::exists(by_stem)) return by_stem.string();
  char name[64];
  std::snprintf(name, sizeof(name), "%.6f.png", timestamp_s);
  return (fs::path(masks_dir) / name).string();
}

cv::Mat readDynamicMask(const std::string& path, int width, int height) {
  if (!std::filesystem::exists(path)) return {};
  cv::Mat raw = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (raw.empty()) throw std::runtime_error(path + ": cannot decode mask image");
  if (raw.cols != width || raw.rows != height) {
    throw std::runtime_error(path + ": mask is " + std::to_string(raw.cols) + "x" +
                             std::to_string(raw.rows) + ", expected " + std::to_string(width) +
                             "x" + std::to_string(height));
  }
  cv::Mat mask;
  cv::compare(raw, 255, mask, cv::CMP_EQ);  // 255 where raw == 255, else 0
  return mask;
}

void GivenMaskFilter::beginFrame(const RgbdFrame& frame) {
  mask_ = readDynamicMask(maskPathFor(masks_dir_, next_rgb_path_, frame.timestamp_s),
                          frame.bgr.cols, frame.bgr.rows);
}

MotionFilterOutput GivenMaskFilter::filter(const MotionFilterInput& input) {
  MotionFilterOutput out;
  out.dynamic_mask = mask_;
  const auto& cur = input.matches->cur_px;
  out.match_is_dynamic.assign(cur.size(), 0);
  if (mask_.empty()) return out;
  for (std::size_t i = 0; i < cur.size(); ++i) {
    const int u = static_cast<int>(cur[i].x + 0.5f);
    const int v = static_cast<int>(cur[i].y + 0.5f);
    if (u >= 0 && v >= 0 && u < mask_.cols && v < mask_.rows && mask_.at<uint8_t>(v, u) == 255) {
      out.match_is_dynamic[i] = 1;
    }
  }
  return out;
}

}  // namespace dynamap
