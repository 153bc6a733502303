#pragma once

#include <mutex>

#include <opencv2/dnn.hpp>

namespace dynamap {

/// OpenCV 4.6 runs the convolutions of a small detector slowly: its generic path (im2row, then
/// dot products) takes the 1 x 1 layers and most depthwise ones. This layer runs the stride-1
/// depthwise (3 x 3, 5 x 5) and 1 x 1 convolutions with its own AVX2 kernels (conv_kernels.hpp;
/// Yolo-Fastest-1.1-XL at 256, one thread on an AVX2 EPYC: 21.4 ms a forward pass with OpenCV's
/// layers, 10.9 ms with these), whose outputs agree with OpenCV's layer's to float rounding
/// (tests/fast_paths, with a tolerance). Every other case (another shape, activation or CPU)
/// runs OpenCV's layer, which it wraps and keeps fused alike. Depthwise and 1 x 1 layers get
/// this layer; the others are OpenCV's own.
cv::Ptr<cv::dnn::Layer> createConvolutionLayer(cv::dnn::LayerParams& params);

/// True if `layer` came from createConvolutionLayer as one of these layers.
bool isOwnConvLayer(const cv::Ptr<cv::dnn::Layer>& layer);

/// True if `layer` (finalised and fused in its net) runs its own kernel on a float input of this
/// shape, false if it hands it to OpenCV's layer (or is not one of these layers).
bool runsOwnConvKernel(const cv::Ptr<cv::dnn::Layer>& layer, const cv::dnn::MatShape& input);

/// While alive, "Convolution" layers that OpenCV DNN instantiates come from
/// createConvolutionLayer. OpenCV's layer registry is process-wide: the scopes are serialised,
/// and a net read inside one must have its layers instantiated (Net::getLayer) before it ends.
class ScopedOwnConvLayers {
 public:
  ScopedOwnConvLayers();
  ~ScopedOwnConvLayers();
  ScopedOwnConvLayers(const ScopedOwnConvLayers&) = delete;
  ScopedOwnConvLayers& operator=(const ScopedOwnConvLayers&) = delete;

 private:
  std::unique_lock<std::mutex> lock_;
};

}  // namespace dynamap
