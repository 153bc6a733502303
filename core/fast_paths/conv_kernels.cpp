#include "conv_kernels.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cstddef>
#include <cstring>

#include <opencv2/core/utility.hpp>

namespace dynamap::conv {

namespace {

constexpr int kLanes = 8;         // floats in an AVX2 vector
constexpr int kRowVectors = 4;    // depthwise: output vectors of a row summed side by side
constexpr int kBlockPixels = 16;  // 1 x 1: pixels of a block (two vectors)
constexpr int kBlockOutputs = 6;  // 1 x 1: output channels of a block (12 accumulators)

__attribute__((target("avx2,fma"))) inline __m256 activate(__m256 s, const Activation& a) {
  if (!a.relu) return s;
  const __m256 positive = _mm256_cmp_ps(s, _mm256_setzero_ps(), _CMP_GT_OS);
  return _mm256_blendv_ps(_mm256_mul_ps(s, _mm256_set1_ps(a.slope)), s, positive);
}

/// Lanes [0, n) of a vector: a mask for maskload / maskstore.
__attribute__((target("avx2,fma"))) inline __m256i firstLanes(int n) {
  const __m256i index = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  return _mm256_cmpgt_epi32(_mm256_set1_epi32(n), index);
}

/// Copies the plane into `padded` (zeros around it, rows wide enough for whole vectors).
void padPlane(const DepthwisePlane& job, int k, int pad, int padded_width,
              std::vector<float>& padded) {
  const int padded_height = job.out_height + k - 1;
  padded.assign(static_cast<std::size_t>(padded_width) * padded_height, 0.f);
  for (int y = 0; y < job.height; ++y) {
    const int py = y + pad;
    if (py < 0 || py >= padded_height) continue;
    const int n = std::min(job.width, padded_width - pad);
    std::memcpy(&padded[static_cast<std::size_t>(py) * padded_width + pad],
                job.in + static_cast<std::ptrdiff_t>(y) * job.width, sizeof(float) * n);
  }
}

/// V neighbouring output vectors of row `oy` from x = ox: bias + the K x K taps, one
/// accumulator per vector (independent chains keep the FMA units busy).
template <int K, int V>
__attribute__((target("avx2,fma"))) void depthwiseVectors(const DepthwisePlane& job,
                                                          const float* padded, int padded_width,
                                                          int oy, int ox, const __m256* w,
                                                          const Activation& activation) {
  __m256 acc[V];
  for (int v = 0; v < V; ++v) acc[v] = _mm256_set1_ps(job.bias);
  for (int ky = 0; ky < K; ++ky) {
    const float* row = padded + static_cast<std::ptrdiff_t>(oy + ky) * padded_width + ox;
    for (int kx = 0; kx < K; ++kx) {
      for (int v = 0; v < V; ++v) {
        acc[v] = _mm256_fmadd_ps(w[ky * K + kx], _mm256_loadu_ps(row + v * kLanes + kx), acc[v]);
      }
    }
  }
  float* dst = job.out + static_cast<std::ptrdiff_t>(oy) * job.out_width + ox;
  for (int v = 0; v < V; ++v) {
    const __m256 s = activate(acc[v], activation);
    const int left = job.out_width - ox - v * kLanes;
    if (left >= kLanes) {
      _mm256_storeu_ps(dst + v * kLanes, s);
    } else {
      _mm256_maskstore_ps(dst + v * kLanes, firstLanes(left), s);
    }
  }
}

template <int K>
__attribute__((target("avx2,fma"))) void depthwiseK(const DepthwisePlane& job, int pad,
                                                    const Activation& activation,
                                                    std::vector<float>& padded) {
  const int vectors = (job.out_width + kLanes - 1) / kLanes;
  const int padded_width = vectors * kLanes + K - 1;
  padPlane(job, K, pad, padded_width, padded);
  __m256 w[K * K];
  for (int t = 0; t < K * K; ++t) w[t] = _mm256_set1_ps(job.weights[t]);
  for (int oy = 0; oy < job.out_height; ++oy) {
    int v = 0;
    for (; v + kRowVectors <= vectors; v += kRowVectors) {
      depthwiseVectors<K, kRowVectors>(job, padded.data(), padded_width, oy, v * kLanes, w,
                                       activation);
    }
    for (; v < vectors; ++v) {
      depthwiseVectors<K, 1>(job, padded.data(), padded_width, oy, v * kLanes, w, activation);
    }
  }
}

/// R output channels from `o` of a block of 16 pixels from `p`: bias + the sum over input
/// channels, two vectors per output. `block` holds the block's pixels of every input channel
/// side by side (16 floats each); `tail` < 16 pixels are written masked.
template <int R>
__attribute__((target("avx2,fma"))) void pointwiseBlock(const Pointwise& job, const float* block,
                                                        int o, int p, int tail,
                                                        const Activation& activation) {
  const int cin = job.in_channels;
  __m256 acc0[R], acc1[R];  // pixels 0-7 and 8-15 (two arrays: GCC keeps them in registers)
#pragma GCC unroll 8
  for (int r = 0; r < R; ++r) acc0[r] = acc1[r] = _mm256_set1_ps(job.bias[o + r]);
  const float* w = job.weights + static_cast<std::ptrdiff_t>(o) * cin;  // packed: R per channel
  for (int c = 0; c < cin; ++c, w += R) {
    const __m256 x0 = _mm256_loadu_ps(block + c * kBlockPixels);
    const __m256 x1 = _mm256_loadu_ps(block + c * kBlockPixels + kLanes);
#pragma GCC unroll 8
    for (int r = 0; r < R; ++r) {
      const __m256 wr = _mm256_broadcast_ss(w + r);
      acc0[r] = _mm256_fmadd_ps(wr, x0, acc0[r]);
      acc1[r] = _mm256_fmadd_ps(wr, x1, acc1[r]);
    }
  }
  const __m256i mask0 = firstLanes(tail), mask1 = firstLanes(tail - kLanes);
#pragma GCC unroll 8
  for (int r = 0; r < R; ++r) {
    float* dst = job.out + static_cast<std::ptrdiff_t>(o + r) * job.pixels + p;
    const __m256 s0 = activate(acc0[r], activation), s1 = activate(acc1[r], activation);
    if (tail >= kBlockPixels) {
      _mm256_storeu_ps(dst, s0);
      _mm256_storeu_ps(dst + kLanes, s1);
    } else {
      _mm256_maskstore_ps(dst, mask0, s0);
      _mm256_maskstore_ps(dst + kLanes, mask1, s1);
    }
  }
}

/// The block's pixels of every input channel side by side: read straight from the planes (a
/// plane apart, often a multiple of 4 KiB) they would evict each other from the L1 cache.
/// A partial last block's missing pixels are zeros.
void gatherBlock(const Pointwise& job, int p, int tail, std::vector<float>& block) {
  block.resize(static_cast<std::size_t>(job.in_channels) * kBlockPixels);
  for (int c = 0; c < job.in_channels; ++c) {
    float* dst = &block[static_cast<std::size_t>(c) * kBlockPixels];
    std::memcpy(dst, job.in + static_cast<std::ptrdiff_t>(c) * job.pixels + p,
                sizeof(float) * tail);
    std::fill(dst + tail, dst + kBlockPixels, 0.f);
  }
}

using PointwiseBlockFn = void (*)(const Pointwise&, const float*, int, int, int, const Activation&);
constexpr PointwiseBlockFn kPointwiseBlocks[kBlockOutputs + 1] = {
    nullptr,           pointwiseBlock<1>, pointwiseBlock<2>, pointwiseBlock<3>,
    pointwiseBlock<4>, pointwiseBlock<5>, pointwiseBlock<6>};

}  // namespace

bool cpuHasAvx2Fma() {
  static const bool has =
      cv::checkHardwareSupport(CV_CPU_AVX2) && cv::checkHardwareSupport(CV_CPU_FMA3);
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

void packPointwiseWeights(const float* weights, int out_channels, int in_channels,
                          std::vector<float>& packed) {
  packed.resize(static_cast<std::size_t>(out_channels) * in_channels);
  float* dst = packed.data();
  for (int o = 0; o < out_channels; o += kBlockOutputs) {
    const int rows = std::min(kBlockOutputs, out_channels - o);
    for (int c = 0; c < in_channels; ++c) {
      for (int r = 0; r < rows; ++r)
        *dst++ = weights[static_cast<std::ptrdiff_t>(o + r) * in_channels + c];
    }
  }
}

int pointwiseBlocks(int pixels) { return (pixels + kBlockPixels - 1) / kBlockPixels; }

void pointwise(const Pointwise& job, int block_begin, int block_end, const Activation& activation,
               std::vector<float>& block) {
  for (int b = block_begin; b < block_end; ++b) {
    const int p = b * kBlockPixels, tail = std::min(kBlockPixels, job.pixels - p);
    gatherBlock(job, p, tail, block);
    for (int o = 0; o < job.out_channels; o += kBlockOutputs) {
      const int rows = std::min(kBlockOutputs, job.out_channels - o);
      kPointwiseBlocks[rows](job, block.data(), o, p, tail, activation);
    }
  }
}

}  // namespace dynamap::conv
