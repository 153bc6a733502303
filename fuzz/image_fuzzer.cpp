// libFuzzer target: image decoding paths we own. Input: mode byte, 2-byte little-endian length
// of the first image, first image bytes, second image bytes.
// Mode bit 0 clear: TumSequence::load of one colour + depth pair (with an undistorting camera
// when bit 1 is set); it must never throw and report bad frames as values.
// Mode bit 0 set: the dynamic-mask reader (readDynamicMask), which may throw runtime_error.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "fuzz_util.hpp"
#include "given_masks.hpp"
#include "tum_dataset.hpp"

namespace {

constexpr int kWidth = 8;
constexpr int kHeight = 6;

/// The two-entry sequence, opened once per camera kind; the images are rewritten per input.
const dynamap::TumSequence& sequence(bool distorted) {
  static std::unique_ptr<dynamap::TumSequence> seqs[2];
  auto& seq = seqs[distorted ? 1 : 0];
  if (!seq) {
    const std::string dir = dynamap::fuzz::scratchDir() + (distorted ? "/dist" : "/plain");
    std::filesystem::create_directories(dir);
    dynamap::fuzz::writeScratch(std::string(distorted ? "dist" : "plain") + "/rgb.txt",
                                "1.0 ../rgb.png\n2.0 ../rgb.png\n");
    dynamap::fuzz::writeScratch(std::string(distorted ? "dist" : "plain") + "/depth.txt",
                                "1.0 ../depth.png\n");
    dynamap::DatasetOptions options;
    options.camera.width = kWidth;
    options.camera.height = kHeight;
    options.camera.fx = options.camera.fy = 5.0;
    options.camera.cx = 3.5;
    options.camera.cy = 2.5;
    if (distorted) options.camera.distortion = {0.1, -0.05, 0.001, 0.001, 0.0};
    seq = std::make_unique<dynamap::TumSequence>(dynamap::TumSequence::open(dir, options));
  }
  return *seq;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // Keep OpenCV from decoding huge images a header claims (memory limit of the fuzzer).
  setenv("OPENCV_IO_MAX_IMAGE_PIXELS", "1048576", 1);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 3) return 0;
  const std::uint8_t mode = data[0];
  const std::size_t first_len = std::min<std::size_t>(data[1] | (data[2] << 8), size - 3);
  const std::string first(reinterpret_cast<const char*>(data) + 3, first_len);
  const std::string second(reinterpret_cast<const char*>(data) + 3 + first_len,
                           size - 3 - first_len);
  if ((mode & 1) == 0) {
    dynamap::fuzz::writeScratch("rgb.png", first);
    dynamap::fuzz::writeScratch("depth.png", second);
    const dynamap::TumSequence& seq = sequence((mode & 2) != 0);
    for (std::size_t i = 0; i < seq.size(); ++i) {
      const dynamap::FrameLoad load = seq.load(i);
      if (load.ok) {
        const auto& f = load.frame;
        if (f.bgr.type() != CV_8UC3 || f.depth_m.type() != CV_32FC1 ||
            f.bgr.size() != f.depth_m.size()) {
          dynamap::fuzz::fail("loaded frame with wrong image types or sizes");
        }
      } else if (load.error.empty()) {
        dynamap::fuzz::fail("bad frame without an error message");
      }
    }
    return 0;
  }
  const std::string path = dynamap::fuzz::writeScratch("mask.png", first);
  try {
    const cv::Mat mask = dynamap::readDynamicMask(path, kWidth, kHeight);
    if (!mask.empty() && (mask.cols != kWidth || mask.rows != kHeight || mask.type() != CV_8UC1)) {
      dynamap::fuzz::fail("mask of the wrong size or type");
    }
  } catch (const std::runtime_error&) {
  }
  return 0;
}
