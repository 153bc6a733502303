#include "image_io.hpp"

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "png_gray16.hpp"

namespace dynamap {
namespace {

/// The file as a 16-bit greyscale PNG (png_gray16.hpp); empty when it is not one or cannot be
/// read, for OpenCV to decide.
cv::Mat readGray16Png(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (!file.good() && !file.eof()) return {};
  return decodeGray16Png(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
}

}  // namespace

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
  if (flags == cv::IMREAD_UNCHANGED) image = readGray16Png(path);  // depth images: the fast way
  try {
    if (image.empty()) image = cv::imread(path, flags);
  } catch (const cv::Exception&) {
    image.release();
  }
  if (image.empty() && error) {
    *error = "cannot decode image " + path + " (corrupt or unsupported format)";
  }
  return image;
}

}  // namespace dynamap
