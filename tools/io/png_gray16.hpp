#pragma once
// A decoder for the one PNG form RGB-D depth images use: 16-bit greyscale, not interlaced, no
// palette or transparency. Lossless, so its pixels are libpng's; it skips libpng's per-row
// work: 2.2 ms a 640 x 480 depth image instead of OpenCV's 2.8 (BENCHMARKS.md, session 46).
// Anything else, or anything unusual, is left to OpenCV.

#include <cstddef>
#include <cstdint>

#include <opencv2/core.hpp>

namespace dynamap {

/// Decodes `size` bytes of a 16-bit greyscale PNG into a CV_16UC1 image. Returns an empty Mat
/// when the file is not exactly that form or anything in it is off (another colour type or bit
/// depth, interlacing, a chunk other than IHDR / IDAT / IEND / tEXt / zTXt / iTXt / tIME /
/// pHYs, a CRC or zlib error, short or extra image data, more than `max_pixels` pixels): the
/// caller then asks OpenCV, which decides what such a file is. Thread-safe.
cv::Mat decodeGray16Png(const std::uint8_t* data, std::size_t size,
                        std::size_t max_pixels = std::size_t{1} << 26);

}  // namespace dynamap
