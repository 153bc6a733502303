#include "dynamap/core/dynamic/depthwise_conv_layer.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/dnn/all_layers.hpp>

namespace dynamap {

namespace {

using cv::dnn::ActivationLayer;
using cv::dnn::BaseConvolutionLayer;
using cv::dnn::Layer;
using cv::dnn::MatShape;

constexpr int kLanes = 8;         // floats per AVX2 vector; also OpenCV's taps per FMA group
constexpr int kOpenCvFast = 16;   // OpenCV's depthwise kernel needs width >= 16 + dilation*(k-1)
constexpr int kOpenCvBlock = 32;  // outputs per block of OpenCV's generic path (BLK_SIZE)

bool cpuHasAvx2Fma() {
  static const bool has =
      cv::checkHardwareSupport(CV_CPU_AVX2) && cv::checkHardwareSupport(CV_CPU_FMA3);
  return has;
}

struct PlaneJob {
  const float* in;
  int height, width;
  float* out;
  int out_height, out_width;
  const float* weights;  // k * k, row-major
  float bias;
};

struct KernelShape {
  int k, pad;
  bool relu;
  float relu_slope;
};

/// One channel. Per output pixel, as OpenCV's generic path (im2row rows of k*k taps, zero
/// padded to a multiple of 8, dotted with the weight row by fastConv): tap t goes to lane t % 8
/// of an accumulator that starts at +0 and takes fma(w, x, acc) for each group of 8 taps (the
/// padding taps add 0 * 0); the 8 lanes are summed as ((0+1)+(2+3))+((4+5)+(6+7)); then bias +
/// sum, then leaky ReLU. Here the 8 lanes of a vector are 8 neighbouring output pixels.
template <int K>
__attribute__((target("avx2,fma"))) void depthwisePlane(const PlaneJob& job,
                                                        const KernelShape& shape,
                                                        std::vector<float>& padded) {
  constexpr int k = K, taps = K * K, groups = (taps + kLanes - 1) / kLanes;
  const int vec_width = (job.out_width + kLanes - 1) / kLanes * kLanes;
  const int pw = vec_width + k - 1, ph = job.out_height + k - 1;
  padded.assign(static_cast<std::size_t>(pw) * ph, 0.f);
  for (int y = 0; y < job.height; ++y) {
    const int py = y + shape.pad;
    if (py < 0 || py >= ph) continue;
    const int n = std::min(job.width, pw - shape.pad);
    std::memcpy(&padded[static_cast<std::size_t>(py) * pw + shape.pad],
                job.in + static_cast<std::ptrdiff_t>(y) * job.width, sizeof(float) * n);
  }
  const __m256 zero = _mm256_setzero_ps(), bias = _mm256_set1_ps(job.bias);
  const __m256 slope = _mm256_set1_ps(shape.relu_slope);
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
                ? _mm256_loadu_ps(&padded[static_cast<std::size_t>(oy + t / k) * pw + ox + t % k])
                : zero;
        acc[t % kLanes] = _mm256_fmadd_ps(w[t], x, t < kLanes ? zero : acc[t % kLanes]);
      }
      const __m256 low =
          _mm256_add_ps(_mm256_add_ps(acc[0], acc[1]), _mm256_add_ps(acc[2], acc[3]));
      const __m256 high =
          _mm256_add_ps(_mm256_add_ps(acc[4], acc[5]), _mm256_add_ps(acc[6], acc[7]));
      __m256 s = _mm256_add_ps(bias, _mm256_add_ps(low, high));
      if (shape.relu) {
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

/// Wraps OpenCV's convolution layer: the wrapped layer is finalised and fused exactly as it
/// would be alone (and runs every case this one does not), while this one keeps its own copy of
/// the fused weights, computed with OpenCV's own operations in OpenCV's order.
class DepthwiseConvLayer : public Layer {
 public:
  explicit DepthwiseConvLayer(const cv::dnn::LayerParams& params)
      : inner_(cv::dnn::ConvolutionLayer::create(params)) {
    setParamsFrom(params);
  }

  bool supportBackend(int backend_id) override { return inner_->supportBackend(backend_id); }

  bool getMemoryShapes(const std::vector<MatShape>& inputs, const int required_outputs,
                       std::vector<MatShape>& outputs,
                       std::vector<MatShape>& internals) const override {
    return inner_->getMemoryShapes(inputs, required_outputs, outputs, internals);
  }

  void finalize(cv::InputArrayOfArrays inputs, cv::OutputArrayOfArrays outputs) override {
    inner_->finalize(inputs, outputs);
    const int out_cn = blobs[0].size[0];
    weights_ = blobs[0].reshape(1, out_cn).clone();
    multipliers_.assign(out_cn, 1.0);
    bias_.assign(out_cn, 0.f);
    if (blobs.size() >= 2) {
      const cv::Mat b = blobs[1].reshape(1, out_cn);
      for (int i = 0; i < out_cn; ++i) bias_[i] = b.at<float>(i);
    }
  }

  bool tryFuse(cv::Ptr<Layer>& top) override {
    if (!inner_->tryFuse(top)) return false;
    if (!top.dynamicCast<cv::dnn::BlankLayer>().empty()) return true;
    cv::Mat w, b;
    top->getScaleShift(w, b);
    fuseWeights(w, b);
    return true;
  }

  bool setActivation(const cv::Ptr<ActivationLayer>& layer) override {
    const bool fused = inner_->setActivation(layer);
    if (layer.empty()) {
      activation_.release();
    } else if (fused) {
      activation_ = layer;
    }
    return fused;
  }

  void forward(cv::InputArrayOfArrays inputs_arr, cv::OutputArrayOfArrays outputs_arr,
               cv::OutputArrayOfArrays internals_arr) override {
    std::vector<cv::Mat> inputs, outputs;
    inputs_arr.getMatVector(inputs);
    outputs_arr.getMatVector(outputs);
    KernelShape shape{};
    if (!ownPath(inputs, outputs, shape)) {
      inner_->forward(inputs_arr, outputs_arr, internals_arr);
      return;
    }
    const cv::Mat& in = inputs[0];
    cv::Mat& out = outputs[0];
    const int channels = in.size[1], planes = in.size[0] * channels;
    cv::parallel_for_(cv::Range(0, planes), [&](const cv::Range& r) {
      std::vector<float> padded;
      for (int p = r.start; p < r.end; ++p) {
        const int n = p / channels, c = p % channels;
        const PlaneJob job{in.ptr<float>(n, c),
                           in.size[2],
                           in.size[3],
                           out.ptr<float>(n, c),
                           out.size[2],
                           out.size[3],
                           weights_.ptr<float>(c),
                           bias_[static_cast<std::size_t>(c)]};
        if (shape.k == 3) {
          depthwisePlane<3>(job, shape, padded);
        } else {
          depthwisePlane<5>(job, shape, padded);
        }
      }
    });
  }

  int64 getFLOPS(const std::vector<MatShape>& inputs,
                 const std::vector<MatShape>& outputs) const override {
    return inner_->getFLOPS(inputs, outputs);
  }

  bool runsOwnKernel(const MatShape& input) const {
    std::vector<MatShape> outs, internals;
    inner_->getMemoryShapes({input}, 1, outs, internals);  // false = not in place
    if (outs.size() != 1) return false;
    const std::vector<cv::Mat> in{cv::Mat(input, CV_32F)}, out{cv::Mat(outs[0], CV_32F)};
    KernelShape shape{};
    return ownPath(in, out, shape);
  }

  bool isDepthwise() const {
    return blobs.size() >= 1 && blobs[0].dims == 4 && blobs[0].size[1] == 1;
  }

 private:
  // As OpenCV's ConvolutionLayerImpl::fuseWeights: (conv(I) + b1) * w + b2.
  void fuseWeights(const cv::Mat& w_in, const cv::Mat& b_in) {
    const int out_cn = weights_.rows;
    const cv::Mat w =
        w_in.total() == 1 ? cv::Mat(1, out_cn, CV_32F, cv::Scalar(w_in.at<float>(0))) : w_in;
    const cv::Mat b =
        b_in.total() == 1 ? cv::Mat(1, out_cn, CV_32F, cv::Scalar(b_in.at<float>(0))) : b_in;
    if (!w.empty()) {
      const cv::Mat origin = blobs[0].reshape(1, out_cn);
      for (int i = 0; i < out_cn; ++i) {
        const double wi = w.at<float>(i);
        multipliers_[i] *= wi;
        cv::Mat row = weights_.row(i);
        cv::multiply(origin.row(i), multipliers_[i], row);
        bias_[i] *= wi;
      }
    }
    if (!b.empty()) {
      for (int i = 0; i < out_cn; ++i) bias_[i] += b.at<float>(i);
    }
  }

  // The cases OpenCV 4.6 runs through its generic path (see the header): 3 x 3 or 5 x 5, stride
  // 1, no dilation, one image plane per group, no activation or a (leaky) ReLU.
  bool ownPath(const std::vector<cv::Mat>& inputs, const std::vector<cv::Mat>& outputs,
               KernelShape& shape) const {
    if (!cpuHasAvx2Fma() || inputs.size() != 1 || outputs.size() != 1 || !isDepthwise()) {
      return false;
    }
    const cv::Mat& in = inputs[0];
    const cv::Mat& out = outputs[0];
    if (in.dims != 4 || out.dims != 4 || in.type() != CV_32F || out.type() != CV_32F ||
        !in.isContinuous() || !out.isContinuous() || in.size[1] != blobs[0].size[0] ||
        out.size[1] != in.size[1]) {
      return false;
    }
    const BaseConvolutionLayer& c = *inner_;
    if (c.kernel_size.size() != 2 || c.kernel_size[0] != c.kernel_size[1] ||
        c.strides != std::vector<std::size_t>{1, 1} ||
        c.dilations != std::vector<std::size_t>{1, 1} || c.pads_begin != c.pads_end ||
        c.pads_begin.size() != 2 || c.pads_begin[0] != c.pads_begin[1]) {
      return false;
    }
    const int k = static_cast<int>(c.kernel_size[0]), pad = static_cast<int>(c.pads_begin[0]);
    const bool opencv_fast = k == 3 && in.size[3] >= kOpenCvFast + (k - 1) && pad <= 1;
    // OpenCV's generic path works in blocks of 32 outputs of a plane; a last block of 1-3
    // outputs takes a scalar loop that sums in another order, and many threads split planes.
    const int tail = out.size[2] * out.size[3] % kOpenCvBlock;
    if ((tail > 0 && tail < 4) || cv::getNumThreads() >= 2 * in.size[0] * in.size[1]) return false;
    if (opencv_fast || (k != 3 && k != 5) || out.size[2] != in.size[2] + 2 * pad - k + 1 ||
        out.size[3] != in.size[3] + 2 * pad - k + 1) {
      return false;
    }
    const auto relu = activation_.dynamicCast<cv::dnn::ReLULayer>();
    if (!activation_.empty() && relu.empty()) return false;
    shape = {k, pad, !relu.empty(), relu.empty() ? 1.f : relu->negativeSlope};
    return true;
  }

  cv::Ptr<BaseConvolutionLayer> inner_;
  cv::Ptr<ActivationLayer> activation_;
  cv::Mat weights_;                  // fused, out_cn x k*k
  std::vector<double> multipliers_;  // as OpenCV's weightsMultipliers
  std::vector<float> bias_;
};

std::mutex& registryMutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace

cv::Ptr<Layer> createConvolutionLayer(cv::dnn::LayerParams& params) {
  const int groups = params.get<int>("group", 1);
  const int outputs = params.get<int>("num_output", 0);
  const bool depthwise = groups > 1 && groups == outputs && !params.blobs.empty() &&
                         params.blobs[0].dims == 4 && params.blobs[0].size[1] == 1;
  if (!depthwise) return cv::dnn::ConvolutionLayer::create(params);
  return cv::makePtr<DepthwiseConvLayer>(params);
}

bool isOwnDepthwiseLayer(const cv::Ptr<Layer>& layer) {
  const auto own = layer.dynamicCast<DepthwiseConvLayer>();
  return !own.empty() && own->isDepthwise();
}

bool runsOwnDepthwiseKernel(const cv::Ptr<Layer>& layer, const MatShape& input) {
  const auto own = layer.dynamicCast<DepthwiseConvLayer>();
  return !own.empty() && own->runsOwnKernel(input);
}

ScopedDepthwiseConvLayers::ScopedDepthwiseConvLayers() : lock_(registryMutex()) {
  cv::dnn::LayerFactory::registerLayer("Convolution", &createConvolutionLayer);
}

ScopedDepthwiseConvLayers::~ScopedDepthwiseConvLayers() {
  cv::dnn::LayerFactory::unregisterLayer("Convolution");
}

}  // namespace dynamap
