#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "dynamap/system/atomic_file.hpp"  // writeTextFileAtomic

namespace dynamap {

/// Encodes `image` in the format given by the extension of `path` (e.g. ".png") and writes
/// it atomically (tmp + rename). Throws std::runtime_error naming the path on failure.
void writeImageAtomic(const std::string& path, const cv::Mat& image);

/// Reads an image with OpenCV `flags`. Returns an empty Mat and sets `*error` (naming the
/// path) when the file is missing or cannot be decoded. Never throws.
cv::Mat readImage(const std::string& path, int flags, std::string* error);

}  // namespace dynamap
