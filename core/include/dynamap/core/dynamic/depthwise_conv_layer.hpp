#pragma once

#include <mutex>

#include <opencv2/dnn.hpp>

namespace dynamap {

/// OpenCV 4.6 runs a depthwise convolution through its fast depthwise kernel only for 3 x 3
/// kernels on planes at least 18 pixels wide; smaller planes (a 256 x 256 Yolo-Fastest's 16 x 16
/// and 8 x 8 stages) and 5 x 5 kernels go through its generic im2row + dot-product path, at about
/// 1 GMAC/s. This layer computes those stride-1 depthwise convolutions straight from a padded
/// plane, 8 output pixels per AVX2 vector, with OpenCV's own arithmetic in OpenCV's order (the
/// same fused multiply-adds per 8-tap group, the same pairwise sum, bias and ReLU), so its
/// outputs are bit for bit those of OpenCV's layer. Every other case (another path, activation,
/// CPU or shape) runs OpenCV's layer, which it wraps and keeps fused alike.
cv::Ptr<cv::dnn::Layer> createConvolutionLayer(cv::dnn::LayerParams& params);

/// True if `layer` came from createConvolutionLayer and is a depthwise convolution it may run.
bool isOwnDepthwiseLayer(const cv::Ptr<cv::dnn::Layer>& layer);

/// True if `layer` (finalised and fused in its net) runs its own kernel on a float input of this
/// shape, false if it hands it to OpenCV's layer (or is not one of these layers).
bool runsOwnDepthwiseKernel(const cv::Ptr<cv::dnn::Layer>& layer, const cv::dnn::MatShape& input);

/// While alive, "Convolution" layers that OpenCV DNN instantiates come from
/// createConvolutionLayer. OpenCV's layer registry is process-wide: the scopes are serialised,
/// and a net read inside one must have its layers instantiated (Net::getLayer) before it ends.
class ScopedDepthwiseConvLayers {
 public:
  ScopedDepthwiseConvLayers();
  ~ScopedDepthwiseConvLayers();
  ScopedDepthwiseConvLayers(const ScopedDepthwiseConvLayers&) = delete;
  ScopedDepthwiseConvLayers& operator=(const ScopedDepthwiseConvLayers&) = delete;

 private:
  std::unique_lock<std::mutex> lock_;
};

}  // namespace dynamap
