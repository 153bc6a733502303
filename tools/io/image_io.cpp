#include "image_io.hpp"

#include <filesystem>
#include <stdexcept>
#include <vector>

#include <opencv2/imgcodecs.hpp>

namespace dynamap {

void writeImageAtomic(const std::string& path, const cv::Mat& image) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext.empty()) {
    throw std::runtime_error("cannot write image " + path + ": no file extension");
  }
  std::vector<unsigned char> buffer;
  bool encoded = false;
  try {
    encoded = cv::imencode(ext, image, buffer);
  } catch (const cv::Exception& e) {
    throw std::runtime_error("cannot encode image " + path + ": " + e.what());
  }
  if (!encoded) {
    throw std::runtime_error("cannot encode image " + path);
  }
  writeBytesAtomic(path, reinterpret_cast<const char*>(buffer.data()), buffer.size());
}

cv::Mat readImage(const std::string& path, int flags, std::string* error) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    if (error) *error = "missing image " + path;
    return {};
  }
  cv::Mat image;
  try {
    image = cv::imread(path, flags);
  } catch (const cv::Exception&) {
    image.release();
  }
  if (image.empty() && error) {
    *error = "cannot decode image " + path + " (corrupt or unsupported format)";
  }
  return image;
}

}  // namespace dynamap
