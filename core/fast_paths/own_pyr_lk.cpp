#include "dynamap/fast_paths/own_pyr_lk.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <vector>

#include <opencv2/core/utility.hpp>

namespace dynamap::lk {
namespace {

constexpr int kWidth = 15;  // the window width written here: 8 pixels in lanes, 7 one by one
constexpr int kLanePixels = 8;
constexpr int kTailPixels = kWidth - kLanePixels;
constexpr int kWBits = 14;                    // OpenCV's fixed-point bilinear weights
constexpr float kFltScale = 1.f / (1 << 20);  // its scale of the sums
constexpr float kMinEigThreshold = 1e-4f;     // its default threshold, as float
using Deriv = short;

struct Weights {
  int w00, w01, w10, w11;
};

Weights weightsAt(float a, float b) {
  Weights w{};
  w.w00 = cvRound((1.f - a) * (1.f - b) * (1 << kWBits));
  w.w01 = cvRound(a * (1.f - b) * (1 << kWBits));
  w.w10 = cvRound((1.f - a) * b * (1 << kWBits));
  w.w11 = (1 << kWBits) - w.w00 - w.w01 - w.w10;
  return w;
}

/// The first image's window of one point at one level: per row, I (scaled by 32) at pixels
/// 0..15 as int16 (15 unused), and Ix, Iy at pixels 0..7 and 8..15 as int32.
struct alignas(32) WindowRow {  // alignas: __m256i is only 16-aligned outside AVX code
  __m256i value, dx0, dy0, dx1, dy1;
};
using Window = std::vector<WindowRow>;
static_assert(alignof(WindowRow) == 32);

struct Pair {
  __m256i w0, w1;  // (w00, w01) and (w10, w11) repeated
};

__attribute__((target("avx2"))) Pair pairOf(const Weights& w) {
  const int top = static_cast<int>((static_cast<unsigned>(w.w01) << 16) | (w.w00 & 0xffff));
  const int bottom = static_cast<int>((static_cast<unsigned>(w.w11) << 16) | (w.w10 & 0xffff));
  return {_mm256_set1_epi32(top), _mm256_set1_epi32(bottom)};
}

/// OpenCV's bilinear step on int16 lanes: per pixel (w00 a + w01 b + w10 c + w11 d + half) >>
/// kShift, with a, b the pixel and its right neighbour in the top row, c, d in the bottom row;
/// packed back to int16 in the lanes' order.
template <int kShift>
__attribute__((target("avx2"))) inline __m256i bilinear(__m256i a, __m256i b, __m256i c, __m256i d,
                                                        const Pair& w) {
  const __m256i half = _mm256_set1_epi32(1 << (kShift - 1));
  const __m256i lo = _mm256_srai_epi32(
      _mm256_add_epi32(_mm256_add_epi32(_mm256_madd_epi16(_mm256_unpacklo_epi16(a, b), w.w0), half),
                       _mm256_madd_epi16(_mm256_unpacklo_epi16(c, d), w.w1)),
      kShift);
  const __m256i hi = _mm256_srai_epi32(
      _mm256_add_epi32(_mm256_add_epi32(_mm256_madd_epi16(_mm256_unpackhi_epi16(a, b), w.w0), half),
                       _mm256_madd_epi16(_mm256_unpackhi_epi16(c, d), w.w1)),
      kShift);
  return _mm256_packs_epi32(lo, hi);
}

/// Bilinear value (scaled by 32, as OpenCV keeps it) of 16 neighbouring pixels of an 8-bit row
/// pair. Reads 16 bytes of each row (pixel 15's right neighbour is taken as 0: that pixel is not
/// used).
__attribute__((target("avx2"))) inline __m256i bilinearU8(const std::uint8_t* top,
                                                          const std::uint8_t* bottom,
                                                          const Pair& w) {
  const __m128i t = _mm_loadu_si128(reinterpret_cast<const __m128i*>(top));
  const __m128i u = _mm_loadu_si128(reinterpret_cast<const __m128i*>(bottom));
  return bilinear<kWBits - 5>(_mm256_cvtepu8_epi16(t), _mm256_cvtepu8_epi16(_mm_srli_si128(t, 1)),
                              _mm256_cvtepu8_epi16(u), _mm256_cvtepu8_epi16(_mm_srli_si128(u, 1)),
                              w);  // pixels 0..15 in order
}

/// (Ix, Iy) pairs of 8 pixels and the same shifted by one pixel (the next register's first
/// pixel, or 0 after the last).
__attribute__((target("avx2"))) inline __m256i nextPixel(__m256i v, __m256i after) {
  return _mm256_alignr_epi8(_mm256_permute2x128_si256(v, after, 0x21), v, 4);
}

__attribute__((target("avx2"))) inline __m256i lowShort(__m256i v) {
  return _mm256_srai_epi32(_mm256_slli_epi32(v, 16), 16);
}

/// Row y of an image with its border (y may be negative: OpenCV's pyramids have a window of
/// border on every side).
inline const std::uint8_t* rowOf(const cv::Mat& image, int y) {
  return image.data + static_cast<std::ptrdiff_t>(y) * static_cast<std::ptrdiff_t>(image.step[0]);
}

/// Reads the first image's window at (x0, y0) (its top-left pixel) with weights w and returns
/// OpenCV's A11, A12, A22 sums (before scaling).
__attribute__((target("avx2"))) void readWindow(const cv::Mat& image, const cv::Mat& deriv, int x0,
                                                int y0, const Weights& weights, Window& win,
                                                float& a11, float& a12, float& a22) {
  const Pair w = pairOf(weights);
  const auto rows = static_cast<int>(win.size());
  __m128 q11 = _mm_setzero_ps(), q12 = _mm_setzero_ps(), q22 = _mm_setzero_ps();
  float s11 = 0.f, s12 = 0.f, s22 = 0.f;
  alignas(32) float t11[8], t12[8], t22[8];
  const __m256i zero = _mm256_setzero_si256();
  for (int y = 0; y < rows; ++y) {
    const std::uint8_t* src = rowOf(image, y0 + y) + x0;
    win[y].value = bilinearU8(src, src + image.step[0], w);
    const auto* d = reinterpret_cast<const Deriv*>(rowOf(deriv, y0 + y)) + 2 * x0;
    const auto* e = reinterpret_cast<const Deriv*>(rowOf(deriv, y0 + y + 1)) + 2 * x0;
    const __m256i a0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(d));
    const __m256i a1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(d + 16));
    const __m256i c0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(e));
    const __m256i c1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(e + 16));
    const __m256i d0 =
        bilinear<kWBits>(a0, nextPixel(a0, a1), c0, nextPixel(c0, c1), w);  // Ix0 Iy0 ..
    const __m256i d1 = bilinear<kWBits>(a1, nextPixel(a1, zero), c1, nextPixel(c1, zero), w);
    win[y].dx0 = lowShort(d0);
    win[y].dy0 = _mm256_srai_epi32(d0, 16);
    win[y].dx1 = lowShort(d1);
    win[y].dy1 = _mm256_srai_epi32(d1, 16);
    // Pixels 0..7: four lanes, pixels 0..3 then 4..7, each a product then a sum.
    const __m256 fx = _mm256_cvtepi32_ps(win[y].dx0), fy = _mm256_cvtepi32_ps(win[y].dy0);
    const __m256 m22 = _mm256_mul_ps(fy, fy), m12 = _mm256_mul_ps(fx, fy),
                 m11 = _mm256_mul_ps(fx, fx);
    q22 = _mm_add_ps(q22, _mm256_castps256_ps128(m22));
    q12 = _mm_add_ps(q12, _mm256_castps256_ps128(m12));
    q11 = _mm_add_ps(q11, _mm256_castps256_ps128(m11));
    q22 = _mm_add_ps(q22, _mm256_extractf128_ps(m22, 1));
    q12 = _mm_add_ps(q12, _mm256_extractf128_ps(m12, 1));
    q11 = _mm_add_ps(q11, _mm256_extractf128_ps(m11, 1));
    // Pixels 8..14: integer products as float, summed one by one.
    _mm256_store_ps(t11, _mm256_cvtepi32_ps(_mm256_mullo_epi32(win[y].dx1, win[y].dx1)));
    _mm256_store_ps(t12, _mm256_cvtepi32_ps(_mm256_mullo_epi32(win[y].dx1, win[y].dy1)));
    _mm256_store_ps(t22, _mm256_cvtepi32_ps(_mm256_mullo_epi32(win[y].dy1, win[y].dy1)));
    for (int k = 0; k < kTailPixels; ++k) {
      s11 += t11[k];
      s12 += t12[k];
      s22 += t22[k];
    }
  }
  const auto reduce = [](__m128 q) {  // OpenCV's v_reduce_sum: (0 + 2) + (1 + 3)
    alignas(16) float v[4];
    _mm_store_ps(v, q);
    return (v[0] + v[2]) + (v[1] + v[3]);
  };
  a11 = s11 + reduce(q11);
  a12 = s12 + reduce(q12);
  a22 = s22 + reduce(q22);
}

/// OpenCV's b1, b2 sums (before scaling) of the window against the second image at (x0, y0).
__attribute__((target("avx2"))) void mismatch(const cv::Mat& image, int x0, int y0,
                                              const Weights& weights, const Window& win, float& b1,
                                              float& b2) {
  const Pair w = pairOf(weights);
  const auto rows = static_cast<int>(win.size());
  __m256 qb = _mm256_setzero_ps();  // OpenCV's qb0 | qb1
  float s1 = 0.f, s2 = 0.f;
  alignas(32) float t1[8], t2[8];
  for (int y = 0; y < rows; ++y) {
    const std::uint8_t* src = rowOf(image, y0 + y) + x0;
    const __m256i diff = _mm256_subs_epi16(bilinearU8(src, src + image.step[0], w), win[y].value);
    const __m256i it0 = _mm256_cvtepi16_epi32(_mm256_castsi256_si128(diff));
    const __m256i it1 = _mm256_cvtepi16_epi32(_mm256_extracti128_si256(diff, 1));
    // Pixels 0..7: OpenCV's lanes hold pixel pairs (0, 4), (1, 5) in qb0, (2, 6), (3, 7) in qb1.
    const __m256i px = _mm256_mullo_epi32(it0, win[y].dx0);
    const __m256i py = _mm256_mullo_epi32(it0, win[y].dy0);
    const __m128i sx = _mm_add_epi32(_mm256_castsi256_si128(px), _mm256_extracti128_si256(px, 1));
    const __m128i sy = _mm_add_epi32(_mm256_castsi256_si128(py), _mm256_extracti128_si256(py, 1));
    const __m256i terms = _mm256_set_m128i(_mm_unpackhi_epi32(sx, sy), _mm_unpacklo_epi32(sx, sy));
    qb = _mm256_add_ps(qb, _mm256_cvtepi32_ps(terms));
    // Pixels 8..14, one by one.
    _mm256_store_ps(t1, _mm256_cvtepi32_ps(_mm256_mullo_epi32(it1, win[y].dx1)));
    _mm256_store_ps(t2, _mm256_cvtepi32_ps(_mm256_mullo_epi32(it1, win[y].dy1)));
    for (int k = 0; k < kTailPixels; ++k) {
      s1 += t1[k];
      s2 += t2[k];
    }
  }
  alignas(16) float q[4];
  _mm_store_ps(q, _mm_add_ps(_mm256_castps256_ps128(qb), _mm256_extractf128_ps(qb, 1)));
  // OpenCV interleaves the lanes to (x, x, y, y) sums and reduces each half with zeros.
  b1 = s1 + ((q[0] + 0.f) + (q[2] + 0.f));
  b2 = s2 + ((q[1] + 0.f) + (q[3] + 0.f));
}

/// One level for one point, as OpenCV's LKTrackerInvoker.
void trackPoint(const cv::Mat& first, const cv::Mat& deriv, const cv::Mat& second,
                cv::Point2f prev_pt, cv::Point2f& next_out, std::uint8_t& status, cv::Size win_size,
                int level, int max_level, int max_count, double epsilon, Window& win) {
  const cv::Point2f half_win((win_size.width - 1) * 0.5f, (win_size.height - 1) * 0.5f);
  cv::Point2f prev = prev_pt * static_cast<float>(1. / (1 << level));
  cv::Point2f next =
      level == max_level ? next_out * static_cast<float>(1. / (1 << level)) : next_out * 2.f;
  next_out = next;
  prev -= half_win;
  const cv::Point2i iprev(cvFloor(prev.x), cvFloor(prev.y));
  if (iprev.x < -win_size.width || iprev.x >= deriv.cols || iprev.y < -win_size.height ||
      iprev.y >= deriv.rows) {
    if (level == 0) status = 0;
    return;
  }
  float a11 = 0.f, a12 = 0.f, a22 = 0.f;
  readWindow(first, deriv, iprev.x, iprev.y,
             weightsAt(prev.x - static_cast<float>(iprev.x), prev.y - static_cast<float>(iprev.y)),
             win, a11, a12, a22);
  const float g11 = a11 * kFltScale, g12 = a12 * kFltScale, g22 = a22 * kFltScale;
  const float det = g11 * g22 - g12 * g12;
  const float min_eig = (g22 + g11 - std::sqrt((g11 - g22) * (g11 - g22) + 4.f * g12 * g12)) /
                        static_cast<float>(2 * win_size.width * win_size.height);
  if (min_eig < kMinEigThreshold || det < FLT_EPSILON) {
    if (level == 0) status = 0;
    return;
  }
  const float inv_det = 1.f / det;
  next -= half_win;
  cv::Point2f prev_delta;
  for (int j = 0; j < max_count; ++j) {
    const cv::Point2i inext(cvFloor(next.x), cvFloor(next.y));
    if (inext.x < -win_size.width || inext.x >= second.cols || inext.y < -win_size.height ||
        inext.y >= second.rows) {
      if (level == 0) status = 0;
      break;
    }
    float b1 = 0.f, b2 = 0.f;
    mismatch(second, inext.x, inext.y,
             weightsAt(next.x - static_cast<float>(inext.x), next.y - static_cast<float>(inext.y)),
             win, b1, b2);
    b1 *= kFltScale;
    b2 *= kFltScale;
    const cv::Point2f delta(static_cast<float>((g12 * b2 - g22 * b1) * inv_det),
                            static_cast<float>((g12 * b1 - g11 * b2) * inv_det));
    next += delta;
    next_out = next + half_win;
    if (delta.ddot(delta) <= epsilon) break;
    if (j > 0 && std::abs(delta.x + prev_delta.x) < 0.01 &&
        std::abs(delta.y + prev_delta.y) < 0.01) {
      next_out -= delta * 0.5f;
      break;
    }
    prev_delta = delta;
  }
}

/// Levels of a pyramid that cv::buildOpticalFlowPyramid built with derivatives, or -1.
int derivLevels(const std::vector<cv::Mat>& pyramid) {
  const int last = static_cast<int>(pyramid.size()) - 1;
  if (last < 1 || last % 2 != 1 || pyramid[0].type() != CV_8UC1 || pyramid[1].type() != CV_16SC2) {
    return -1;
  }
  return last / 2;
}

}  // namespace

bool ownPyrLkUsable(cv::Size window) {
#if defined(__x86_64__)
  static const bool cpu = cv::checkHardwareSupport(CV_CPU_AVX2);
  return cpu && window.width == kWidth && window.height >= 3;
#else
  (void)window;
  return false;
#endif
}

void ownPyrLk(const std::vector<cv::Mat>& prev, const std::vector<cv::Mat>& next,
              const std::vector<cv::Point2f>& prev_px, std::vector<cv::Point2f>& next_px,
              std::vector<std::uint8_t>& status, cv::Size window, int max_level,
              const cv::TermCriteria& criteria) {
  const int prev_levels = derivLevels(prev), next_levels = derivLevels(next);
  CV_Assert(prev_levels >= 0 && next_levels >= 0 && ownPyrLkUsable(window));
  CV_Assert(next_px.size() == prev_px.size());
  status.assign(prev_px.size(), 1);
  if (prev_px.empty()) return;
  const int top = std::min({std::max(max_level, 0), prev_levels, next_levels});
  const int max_count = (criteria.type & cv::TermCriteria::COUNT) == 0
                            ? 30
                            : std::min(std::max(criteria.maxCount, 0), 100);
  double epsilon = (criteria.type & cv::TermCriteria::EPS) == 0
                       ? 0.01
                       : std::min(std::max(criteria.epsilon, 0.), 10.);
  epsilon *= epsilon;
  Window win(static_cast<std::size_t>(window.height));
  for (int level = top; level >= 0; --level) {
    const cv::Mat& first = prev[static_cast<std::size_t>(level) * 2];
    const cv::Mat& deriv = prev[static_cast<std::size_t>(level) * 2 + 1];
    const cv::Mat& second = next[static_cast<std::size_t>(level) * 2];
    CV_Assert(first.size() == second.size() && first.type() == second.type());
    for (std::size_t i = 0; i < prev_px.size(); ++i) {
      trackPoint(first, deriv, second, prev_px[i], next_px[i], status[i], window, level, top,
                 max_count, epsilon, win);
    }
  }
}

}  // namespace dynamap::lk
