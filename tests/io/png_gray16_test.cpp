// The 16-bit greyscale PNG decoder (tools/io/png_gray16.hpp): the same pixels as OpenCV on
// every filter and on the sequences' depth images, and an empty answer (OpenCV decides) for
// anything else.
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <zlib.h>
#include <opencv2/imgcodecs.hpp>

#include "../common/test_paths.hpp"
#include "image_io.hpp"
#include "png_gray16.hpp"

namespace dynamap {
namespace {

using Bytes = std::vector<std::uint8_t>;

void put32(Bytes& out, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<std::uint8_t>(v >> s));
}

void putChunk(Bytes& out, const char* type, const Bytes& body) {
  put32(out, static_cast<std::uint32_t>(body.size()));
  const std::size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), body.begin(), body.end());
  put32(out, static_cast<std::uint32_t>(crc32(0L, out.data() + start, 4 + body.size())));
}

int paethPredictor(int a, int b, int c) {
  const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
  return (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
}

/// Filters one row of big-endian bytes with PNG filter `f` (2 bytes a pixel).
Bytes filterRow(int f, const Bytes& row, const Bytes& up) {
  Bytes out(row.size());
  for (std::size_t i = 0; i < row.size(); ++i) {
    const int a = i >= 2 ? row[i - 2] : 0, b = up[i], c = i >= 2 ? up[i - 2] : 0;
    const int pred = f == 0   ? 0
                     : f == 1 ? a
                     : f == 2 ? b
                     : f == 3 ? (a + b) / 2
                              : paethPredictor(a, b, c);
    out[i] = static_cast<std::uint8_t>(row[i] - pred);
  }
  return out;
}

struct PngSpec {
  int bit_depth = 16, colour_type = 0, interlace = 0;
  std::vector<int> filters{0, 1, 2, 3, 4};  ///< per row, cycled
};

/// A PNG of `image` (CV_16UC1) written by hand: every row with the filter the spec gives.
Bytes makePng(const cv::Mat& image, const PngSpec& spec = {}) {
  Bytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  Bytes ihdr;
  put32(ihdr, static_cast<std::uint32_t>(image.cols));
  put32(ihdr, static_cast<std::uint32_t>(image.rows));
  ihdr.insert(ihdr.end(), {static_cast<std::uint8_t>(spec.bit_depth),
                           static_cast<std::uint8_t>(spec.colour_type), 0, 0,
                           static_cast<std::uint8_t>(spec.interlace)});
  putChunk(png, "IHDR", ihdr);
  Bytes raw, up(static_cast<std::size_t>(image.cols) * 2, 0);
  for (int y = 0; y < image.rows; ++y) {
    Bytes row;
    for (int x = 0; x < image.cols; ++x) {
      const std::uint16_t v = image.at<std::uint16_t>(y, x);
      row.push_back(static_cast<std::uint8_t>(v >> 8));
      row.push_back(static_cast<std::uint8_t>(v & 0xff));
    }
    const int f = spec.filters[static_cast<std::size_t>(y) % spec.filters.size()];
    raw.push_back(static_cast<std::uint8_t>(f));
    const Bytes filtered = filterRow(f, row, up);
    raw.insert(raw.end(), filtered.begin(), filtered.end());
    up = row;
  }
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  Bytes packed(packed_size);
  EXPECT_EQ(compress(packed.data(), &packed_size, raw.data(), static_cast<uLong>(raw.size())),
            Z_OK);
  packed.resize(packed_size);
  // Two IDAT chunks: the stream may be split anywhere.
  const std::size_t half = packed.size() / 2;
  putChunk(png, "IDAT", Bytes(packed.begin(), packed.begin() + static_cast<std::ptrdiff_t>(half)));
  putChunk(png, "IDAT", Bytes(packed.begin() + static_cast<std::ptrdiff_t>(half), packed.end()));
  putChunk(png, "IEND", {});
  return png;
}

cv::Mat randomDepth(int rows, int cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> value(0, 65535), step(-300, 300);
  cv::Mat image(rows, cols, CV_16UC1);
  for (int y = 0; y < rows; ++y) {
    int v = value(rng);
    for (int x = 0; x < cols; ++x) {  // smooth runs and jumps, as depth has
      v = (x % 17 == 0) ? value(rng) : std::clamp(v + step(rng), 0, 65535);
      image.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(v);
    }
  }
  return image;
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() && cv::countNonZero(a != b) == 0;
}

cv::Mat decode(const Bytes& png) { return decodeGray16Png(png.data(), png.size()); }

TEST(PngGray16, EveryFilterDecodesToThePixels) {
  const cv::Mat image = randomDepth(23, 37, 7);  // odd sizes
  for (int f = 0; f <= 4; ++f) {
    PngSpec spec;
    spec.filters = {f};
    EXPECT_TRUE(same(decode(makePng(image, spec)), image)) << "filter " << f;
  }
  const Bytes mixed = makePng(image);  // rows cycle through all five
  EXPECT_TRUE(same(decode(mixed), image));
  EXPECT_TRUE(same(cv::imdecode(mixed, cv::IMREAD_UNCHANGED), image));  // and OpenCV agrees
}

TEST(PngGray16, MatchesOpenCvOnWhatOpenCvWrites) {
  for (const int level : {1, 6, 9}) {  // libpng picks the row filters itself
    const cv::Mat image = randomDepth(48, 64, static_cast<unsigned>(level));
    std::vector<std::uint8_t> png;
    ASSERT_TRUE(cv::imencode(".png", image, png, {cv::IMWRITE_PNG_COMPRESSION, level}));
    EXPECT_TRUE(same(decode(png), image)) << "compression " << level;
  }
}

TEST(PngGray16, MatchesOpenCvOnTheSequencesDepthImages) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  // Real sensor files (Sub filter only) and semi-synthetic ones (all five filters).
  const char* sequences[] = {"tum/rgbd_dataset_freiburg3_teddy", "bonn/rgbd_bonn_crowd_400_499",
                             "dynamic/teddy_dyn_crowd_dev"};
  for (const char* sequence : sequences) {
    std::vector<std::filesystem::path> files;
    for (const auto& e :
         std::filesystem::directory_iterator(test::sharedData() / sequence / "depth"))
      files.push_back(e.path());
    std::sort(files.begin(), files.end());
    ASSERT_GE(files.size(), 10u) << sequence;
    for (std::size_t i = 0; i < files.size(); i += files.size() / 10) {
      std::ifstream in(files[i], std::ios::binary);
      const Bytes bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      const cv::Mat ours = decode(bytes);
      ASSERT_FALSE(ours.empty()) << files[i];
      EXPECT_TRUE(same(ours, cv::imread(files[i].string(), cv::IMREAD_UNCHANGED))) << files[i];
    }
  }
}

TEST(PngGray16, LeavesEveryOtherFormOrFaultToOpenCv) {
  const cv::Mat image = randomDepth(8, 9, 3);
  const Bytes good = makePng(image);
  ASSERT_FALSE(decode(good).empty());
  PngSpec eight;
  eight.bit_depth = 8;
  EXPECT_TRUE(decode(makePng(image, eight)).empty());
  PngSpec rgb;
  rgb.colour_type = 2;
  EXPECT_TRUE(decode(makePng(image, rgb)).empty());
  PngSpec interlaced;
  interlaced.interlace = 1;
  EXPECT_TRUE(decode(makePng(image, interlaced)).empty());
  PngSpec bad_filter;
  bad_filter.filters = {5};
  EXPECT_TRUE(decode(makePng(image, bad_filter)).empty());

  Bytes crc = good;
  crc[crc.size() - 20] ^= 1;  // a byte of the last IDAT
  EXPECT_TRUE(decode(crc).empty());
  EXPECT_TRUE(decode(Bytes(good.begin(), good.end() - 12)).empty());  // no IEND
  Bytes trailing = good;
  trailing.push_back(0);
  EXPECT_TRUE(decode(trailing).empty());
  // A chunk it does not know (tRNS would make OpenCV add alpha) before the data.
  Bytes with_trns(good.begin(), good.begin() + 33);  // signature + IHDR
  putChunk(with_trns, "tRNS", {0, 0});
  with_trns.insert(with_trns.end(), good.begin() + 33, good.end());
  EXPECT_TRUE(decode(with_trns).empty());
  Bytes with_text(good.begin(), good.begin() + 33);  // a text chunk changes nothing
  putChunk(with_text, "tEXt", {'a', 0, 'b'});
  with_text.insert(with_text.end(), good.begin() + 33, good.end());
  EXPECT_TRUE(same(decode(with_text), image));
  EXPECT_TRUE(decodeGray16Png(good.data(), good.size(), 8 * 9 - 1).empty());  // too many pixels
}

TEST(PngGray16, ReadImageFallsBackToOpenCvAndNamesTheFile) {
  const auto dir = test::freshTempDir("png_gray16");
  const cv::Mat image = randomDepth(6, 5, 11);
  const auto write = [&](const std::string& name, const Bytes& bytes) {
    const std::string path = (dir / name).string();
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    return path;
  };
  std::string error;
  EXPECT_TRUE(
      same(readImage(write("good.png", makePng(image)), cv::IMREAD_UNCHANGED, &error), image));
  EXPECT_TRUE(error.empty());
  const cv::Mat grey8(4, 4, CV_8UC1, cv::Scalar(200));  // not for the fast path: OpenCV reads it
  std::vector<std::uint8_t> png8;
  ASSERT_TRUE(cv::imencode(".png", grey8, png8));
  const cv::Mat read8 = readImage(write("grey8.png", png8), cv::IMREAD_UNCHANGED, &error);
  EXPECT_TRUE(same(read8, grey8));
  Bytes corrupt = makePng(image);
  corrupt[corrupt.size() - 20] ^= 1;
  const std::string corrupt_path = write("corrupt.png", corrupt);
  EXPECT_TRUE(readImage(corrupt_path, cv::IMREAD_UNCHANGED, &error).empty());
  EXPECT_NE(error.find(corrupt_path), std::string::npos) << error;
}

}  // namespace
}  // namespace dynamap
