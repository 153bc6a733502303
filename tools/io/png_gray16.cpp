#include "png_gray16.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

#include <zlib.h>

namespace dynamap {
namespace {

constexpr std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

std::uint32_t bigEndian32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

bool isType(const std::uint8_t* type, const char* name) { return std::memcmp(type, name, 4) == 0; }

/// Ancillary chunks that change nothing in the pixels OpenCV returns for IMREAD_UNCHANGED.
bool harmlessAncillary(const std::uint8_t* type) {
  return isType(type, "tEXt") || isType(type, "zTXt") || isType(type, "iTXt") ||
         isType(type, "tIME") || isType(type, "pHYs");
}

/// The PNG Paeth predictor (PNG spec, section 9.4) on bytes a (left), b (up), c (up-left).
inline int paeth(int a, int b, int c) {
  const int pa = std::abs(b - c);
  const int pb = std::abs(a - c);
  const int pc = std::abs(a + b - 2 * c);
  return (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
}

/// Undoes one row's filter in place; 2 bytes a pixel. up: the row above, already unfiltered
/// (zeros for the first row). False for an unknown filter type.
bool unfilterRow(int filter, std::uint8_t* row, const std::uint8_t* up, std::size_t bytes) {
  switch (filter) {
    case 0:
      return true;
    case 1:
      for (std::size_t i = 2; i < bytes; ++i) row[i] = std::uint8_t(row[i] + row[i - 2]);
      return true;
    case 2:
      for (std::size_t i = 0; i < bytes; ++i) row[i] = std::uint8_t(row[i] + up[i]);
      return true;
    case 3:
      for (std::size_t i = 0; i < 2 && i < bytes; ++i) row[i] = std::uint8_t(row[i] + (up[i] >> 1));
      for (std::size_t i = 2; i < bytes; ++i)
        row[i] = std::uint8_t(row[i] + ((row[i - 2] + up[i]) >> 1));
      return true;
    case 4:
      for (std::size_t i = 0; i < 2 && i < bytes; ++i) row[i] = std::uint8_t(row[i] + up[i]);
      for (std::size_t i = 2; i + 1 < bytes; i += 2) {  // the two bytes of a pixel: two chains
        row[i] = std::uint8_t(row[i] + paeth(row[i - 2], up[i], up[i - 2]));
        row[i + 1] = std::uint8_t(row[i + 1] + paeth(row[i - 1], up[i + 1], up[i - 1]));
      }
      return true;
    default:
      return false;
  }
}

/// Inflates the IDAT chunks' zlib stream into exactly `out_size` bytes.
class Inflater {
 public:
  Inflater(std::uint8_t* out, std::size_t out_size) : out_size_(out_size) {
    stream_.next_out = out;
    stream_.avail_out = static_cast<uInt>(out_size);
    ok_ = out_size <= 0xffffffffu && inflateInit(&stream_) == Z_OK;
  }
  ~Inflater() {
    if (ok_) inflateEnd(&stream_);
  }
  Inflater(const Inflater&) = delete;
  Inflater& operator=(const Inflater&) = delete;

  /// Feeds one IDAT chunk; false once anything is wrong (data after the stream's end too).
  bool feed(const std::uint8_t* data, std::uint32_t size) {
    if (!ok_ || (ended_ && size > 0)) return false;
    stream_.next_in = const_cast<Bytef*>(data);
    stream_.avail_in = size;
    while (stream_.avail_in > 0) {
      const int rc = inflate(&stream_, Z_NO_FLUSH);
      if (rc == Z_STREAM_END) {
        ended_ = true;
        return stream_.avail_in == 0;
      }
      if (rc != Z_OK) return false;
    }
    return true;
  }
  bool complete() const { return ok_ && ended_ && stream_.total_out == out_size_; }

 private:
  z_stream stream_{};
  std::size_t out_size_;
  bool ok_ = false;
  bool ended_ = false;
};

}  // namespace

cv::Mat decodeGray16Png(const std::uint8_t* data, std::size_t size, std::size_t max_pixels) {
  if (size < 8 + 25 || std::memcmp(data, kSignature, 8) != 0) return {};
  std::size_t pos = 8;
  int width = 0, height = 0;
  std::size_t row_bytes = 0;
  std::unique_ptr<std::uint8_t[]> raw;  // the inflated rows (not zeroed: inflate fills them)
  std::unique_ptr<Inflater> inflater;
  enum class Stage { kHeader, kBeforeData, kData, kAfterData, kEnd } stage = Stage::kHeader;
  while (pos + 12 <= size && stage != Stage::kEnd) {
    const std::uint32_t length = bigEndian32(data + pos);
    if (length > 0x7fffffffu || length > size - pos - 12) return {};
    const std::uint8_t* type = data + pos + 4;
    const std::uint8_t* body = data + pos + 8;
    const uLong crc = crc32(crc32(0L, type, 4), body, length);
    if (crc != bigEndian32(body + length)) return {};
    pos += 12 + std::size_t{length};
    if (stage == Stage::kHeader) {
      // IHDR: width, height, bit depth 16, colour type 0 (grey), compression, filter and
      // interlace methods 0.
      if (!isType(type, "IHDR") || length != 13) return {};
      const std::uint32_t w = bigEndian32(body), h = bigEndian32(body + 4);
      if (w == 0 || h == 0 || w > 0x7fffffffu / 2 || h > 0x7fffffffu) return {};
      if (std::size_t{w} * h > max_pixels) return {};
      if (body[8] != 16 || body[9] != 0 || body[10] != 0 || body[11] != 0 || body[12] != 0)
        return {};
      width = static_cast<int>(w);
      height = static_cast<int>(h);
      row_bytes = std::size_t{w} * 2;
      const std::size_t raw_size = (row_bytes + 1) * h;
      raw.reset(new std::uint8_t[raw_size]);
      inflater = std::make_unique<Inflater>(raw.get(), raw_size);
      stage = Stage::kBeforeData;
    } else if (isType(type, "IDAT")) {
      if (stage == Stage::kAfterData || !inflater->feed(body, length)) return {};
      stage = Stage::kData;
    } else if (isType(type, "IEND")) {
      if (stage != Stage::kData || length != 0) return {};
      stage = Stage::kEnd;
    } else if (harmlessAncillary(type)) {
      if (stage == Stage::kData) stage = Stage::kAfterData;
    } else {
      return {};
    }
  }
  if (stage != Stage::kEnd || pos != size || !inflater->complete()) return {};
  cv::Mat image(height, width, CV_16UC1);
  const std::vector<std::uint8_t> zeros(row_bytes, 0);
  const std::uint8_t* up = zeros.data();
  for (int y = 0; y < height; ++y) {
    std::uint8_t* line = raw.get() + static_cast<std::size_t>(y) * (row_bytes + 1);
    if (!unfilterRow(line[0], line + 1, up, row_bytes)) return {};
    up = line + 1;
    std::uint16_t* out = image.ptr<std::uint16_t>(y);
    for (int x = 0; x < width; ++x) {
      out[x] = static_cast<std::uint16_t>((line[1 + 2 * x] << 8) | line[2 + 2 * x]);
    }
  }
  return image;
}

}  // namespace dynamap
