#pragma once

#include <vector>

namespace dynamap::conv {

/// Kernels for the convolutions that OpenCV 4.6's generic path (im2row, then dot products)
/// runs slowly: the vector lanes hold neighbouring output pixels. They follow OpenCV's summation
/// order, so results agree with OpenCV's to float rounding (tests/fast_paths, with a tolerance).
/// x86-64 only; callers check the CPU first.
bool cpuHasAvx2Fma();
bool cpuHasAvx512();

struct Activation {
  bool relu = false;
  float slope = 1.f;  ///< ReLU's negative slope
};

/// One channel of a stride-1 depthwise convolution (k = 3 or 5, zero padding `pad`).
struct DepthwisePlane {
  const float* in;
  int height, width;
  float* out;
  int out_height, out_width;
  const float* weights;  ///< k * k, row-major
  float bias;
};
void depthwise(const DepthwisePlane& job, int k, int pad, const Activation& activation,
               std::vector<float>& padded);

/// Output channels [out_begin, out_end) of a 1 x 1 convolution of one image, as OpenCV's
/// AVX-512 fastConv sums them (16 lanes while 16 channels remain, once the input has >= 32).
struct Pointwise {
  const float* in;  ///< in_channels planes of `pixels`
  int in_channels, pixels;
  float* out;            ///< out planes of `pixels`
  const float* weights;  ///< out x in_channels, row-major
  const float* bias;
};
void pointwise(const Pointwise& job, int out_begin, int out_end, const Activation& activation);

}  // namespace dynamap::conv
