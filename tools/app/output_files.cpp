#include "output_files.hpp"

#include <fstream>
#include <sstream>

#include <opencv2/imgproc.hpp>

namespace dynamap {

cv::Mat maskOverlay(const cv::Mat& bgr, const cv::Mat& dynamic_mask) {
  cv::Mat out = bgr.clone();
  if (dynamic_mask.empty()) return out;
  cv::Mat red(bgr.size(), bgr.type(), cv::Scalar(0, 0, 255));
  cv::Mat blended;
  cv::addWeighted(bgr, 0.5, red, 0.5, 0.0, blended);
  blended.copyTo(out, dynamic_mask == 255);
  return out;
}

double peakMemoryMiB() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) {
      std::istringstream ss(line.substr(6));
      double kib = 0.0;
      ss >> kib;
      return kib / 1024.0;
    }
  }
  return 0.0;
}

}  // namespace dynamap
