#include "conv_kernels.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include <opencv2/core/utility.hpp>

namespace dynamap::conv {

namespace {

constexpr int kLanes = 8;  // OpenCV's fastConv sums 8 lanes (after folding 16 into 8)

/// Per output pixel, as OpenCV's generic path (im2row rows of k*k taps, zero padded to a
/// multiple of 8, dotted with the weight row): tap t goes to lane t % 8 of an accumulator that
/// starts at +0 and takes fma(w, x, acc) for each group of 8 taps (the padding taps add 0 * 0);
/// the 8 lanes are summed as ((0+1)+(2+3))+((4+5)+(6+7)); then bias + sum, then leaky ReLU.
/// Here the 8 lanes of a vector are 8 neighbouring output pixels.
template <int K>
__attribute__((target("avx2,fma"))) void depthwiseK(const DepthwisePlane& job, int pad,
                                                    const Activation& activation,
                                                    std::vector<float>& padded) {
  constexpr int taps = K * K, groups = (taps + kLanes - 1) / kLanes;
  const int vec_width = (job.out_width + kLanes - 1) / kLanes * kLanes;
  const int pw = vec_width + K - 1, ph = job.out_height + K - 1;
  padded.assign(static_cast<std::size_t>(pw) * ph, 0.f);
  for (int y = 0; y < job.height; ++y) {
    const int py = y + pad;
    if (py < 0 || py >= ph) continue;
    const int n = std::min(job.width, pw - pad);
    std::memcpy(&padded[static_cast<std::size_t>(py) * pw + pad],
                job.in + static_cast<std::ptrdiff_t>(y) * job.width, sizeof(float) * n);
  }
  const __m256 zero = _mm256_setzero_ps(), bias = _mm256_set1_ps(job.bias);
  const __m256 slope = _mm256_set1_ps(activation.slope);
  __m256 w[groups * kLanes];
  for (int t = 0; t < groups * kLanes; ++t) w[t] = t < taps ? _mm256_set1_ps(job.weights[t]) : zero;
  alignas(32) float tail[kLanes];
  for (int oy = 0; oy < job.out_height; ++oy) {
    for (int ox = 0; ox < vec_width; ox += kLanes) {
      __m256 acc[kLanes];
#pragma GCC unroll 64
      for (int t = 0; t < groups * kLanes; ++t) {
        const __m256 x =
            t < taps
                ? _mm256_loadu_ps(&padded[static_cast<std::size_t>(oy + t / K) * pw + ox + t % K])
                : zero;
        acc[t % kLanes] = _mm256_fmadd_ps(w[t], x, t < kLanes ? zero : acc[t % kLanes]);
      }
      const __m256 low =
          _mm256_add_ps(_mm256_add_ps(acc[0], acc[1]), _mm256_add_ps(acc[2], acc[3]));
      const __m256 high =
          _mm256_add_ps(_mm256_add_ps(acc[4], acc[5]), _mm256_add_ps(acc[6], acc[7]));
      __m256 s = _mm256_add_ps(bias, _mm256_add_ps(low, high));
      if (activation.relu) {
        const __m256 positive = _mm256_cmp_ps(s, zero, _CMP_GT_OS);
        s = _mm256_blendv_ps(_mm256_mul_ps(s, slope), s, positive);
      }
      float* dst = job.out + static_cast<std::ptrdiff_t>(oy) * job.out_width + ox;
      if (ox + kLanes <= job.out_width) {
        _mm256_storeu_ps(dst, s);
      } else {
        _mm256_store_ps(tail, s);
        std::memcpy(dst, tail, sizeof(float) * (job.out_width - ox));
      }
    }
  }
}

/// OpenCV's AVX-512 fastConv, per output: with >= 32 input channels, 16 lanes (channel c in
/// lane c % 16, from +0) while 16 channels remain, folded to 8 as lane l + lane l + 8; the rest
/// (or everything, under 32 channels) in 8 lanes, zero padded to a multiple of 8; then the
/// depthwise case's pairwise sum, bias and ReLU. Here the 16 lanes of a vector are 16 pixels.
__attribute__((target("avx512f,avx2,fma"))) void pointwiseAvx512(const Pointwise& job,
                                                                 int out_begin, int out_end,
                                                                 const Activation& activation) {
  const int cin = job.in_channels, pixels = job.pixels;
  const int wide = cin >= 32 ? cin / 16 : 0;  // OpenCV: k += 16 while k <= cin - 16
  const int narrow_end = (cin + kLanes - 1) / kLanes * kLanes;
  const __m512 zero = _mm512_setzero_ps(), slope = _mm512_set1_ps(activation.slope);
  // The 16 pixels of every input channel are copied together first: read straight from the
  // planes (a plane apart, often a multiple of 4 KiB) they evict each other from the L1 cache.
  std::vector<float> block(static_cast<std::size_t>(cin) * 16 + 16);
  float* x = reinterpret_cast<float*>((reinterpret_cast<std::uintptr_t>(block.data()) + 63) &
                                      ~std::uintptr_t{63});
  const std::ptrdiff_t stride = 16;
  for (int p = 0; p < pixels; p += 16) {
    const __mmask16 mask =
        pixels - p >= 16 ? __mmask16(0xFFFF) : static_cast<__mmask16>((1u << (pixels - p)) - 1);
    for (int c = 0; c < cin; ++c) {
      _mm512_store_ps(x + c * stride,
                      _mm512_maskz_loadu_ps(mask, job.in + std::ptrdiff_t{c} * pixels + p));
    }
    for (int o = out_begin; o < out_end; ++o) {
      const float* w = job.weights + static_cast<std::ptrdiff_t>(o) * cin;
      __m512 b[kLanes];
      if (wide > 0) {
        __m512 a[16];
        for (int l = 0; l < 16; ++l) {
          a[l] = _mm512_fmadd_ps(_mm512_set1_ps(w[l]), _mm512_load_ps(x + l * stride), zero);
        }
        for (int j = 1; j < wide; ++j) {
          for (int l = 0; l < 16; ++l) {
            const int c = 16 * j + l;
            a[l] = _mm512_fmadd_ps(_mm512_set1_ps(w[c]), _mm512_load_ps(x + c * stride), a[l]);
          }
        }
        for (int l = 0; l < kLanes; ++l) b[l] = _mm512_add_ps(a[l], a[l + kLanes]);
      } else {
        for (int l = 0; l < kLanes; ++l) b[l] = zero;
      }
      for (int c0 = 16 * wide; c0 < narrow_end; c0 += kLanes) {
        for (int l = 0; l < kLanes; ++l) {
          const int c = c0 + l;
          b[l] = c < cin
                     ? _mm512_fmadd_ps(_mm512_set1_ps(w[c]), _mm512_load_ps(x + c * stride), b[l])
                     : _mm512_fmadd_ps(zero, zero, b[l]);
        }
      }
      const __m512 low = _mm512_add_ps(_mm512_add_ps(b[0], b[1]), _mm512_add_ps(b[2], b[3]));
      const __m512 high = _mm512_add_ps(_mm512_add_ps(b[4], b[5]), _mm512_add_ps(b[6], b[7]));
      __m512 s = _mm512_add_ps(_mm512_set1_ps(job.bias[o]), _mm512_add_ps(low, high));
      if (activation.relu) {
        const __mmask16 positive = _mm512_cmp_ps_mask(s, zero, _CMP_GT_OS);
        s = _mm512_mask_blend_ps(positive, _mm512_mul_ps(s, slope), s);
      }
      _mm512_mask_storeu_ps(job.out + static_cast<std::ptrdiff_t>(o) * pixels + p, mask, s);
    }
  }
}

}  // namespace

bool cpuHasAvx2Fma() {
  static const bool has =
      cv::checkHardwareSupport(CV_CPU_AVX2) && cv::checkHardwareSupport(CV_CPU_FMA3);
  return has;
}

bool cpuHasAvx512() {
  static const bool has = cpuHasAvx2Fma() && cv::checkHardwareSupport(CV_CPU_AVX512_SKX);
  return has;
}

void depthwise(const DepthwisePlane& job, int k, int pad, const Activation& activation,
               std::vector<float>& padded) {
  if (k == 3) {
    depthwiseK<3>(job, pad, activation, padded);
  } else {
    depthwiseK<5>(job, pad, activation, padded);
  }
}

void pointwise(const Pointwise& job, int out_begin, int out_end, const Activation& activation) {
  pointwiseAvx512(job, out_begin, out_end, activation);
}

}  // namespace dynamap::conv
