#pragma once

#include <vector>

namespace dynamap::conv {

/// AVX2 + FMA kernels for the detector's stride-1 depthwise and 1 x 1 convolutions, which
/// OpenCV 4.6 runs slowly (im2row, then dot products): the vector lanes hold neighbouring output
/// pixels. Their sums run in another order than OpenCV's, so results agree with its layer's to
/// float rounding (tests/fast_paths, with a tolerance). x86-64 only; callers check the CPU first.
bool cpuHasAvx2Fma();

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

/// A 1 x 1 convolution of one image, in blocks of 16 pixels (the last one partial).
struct Pointwise {
  const float* in;  ///< in_channels planes of `pixels`
  int in_channels, pixels;
  float* out;  ///< out_channels planes of `pixels`
  int out_channels;
  const float* weights;  ///< as packPointwiseWeights() leaves them
  const float* bias;
};
/// Out x in row-major weights in the order the kernel reads them: for each block of 6 output
/// channels, the block's weights of input channel 0, then of 1, ...
void packPointwiseWeights(const float* weights, int out_channels, int in_channels,
                          std::vector<float>& packed);
int pointwiseBlocks(int pixels);
/// Every output channel of pixel blocks [block_begin, block_end); `block` is scratch.
void pointwise(const Pointwise& job, int block_begin, int block_end, const Activation& activation,
               std::vector<float>& block);

}  // namespace dynamap::conv
