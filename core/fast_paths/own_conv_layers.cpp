#include "dynamap/fast_paths/own_conv_layers.hpp"

#include <algorithm>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/dnn/all_layers.hpp>

#include "conv_kernels.hpp"

namespace dynamap {

namespace {

using cv::dnn::ActivationLayer;
using cv::dnn::BaseConvolutionLayer;
using cv::dnn::Layer;
using cv::dnn::MatShape;

enum class OwnKernel { kNone, kDepthwise, kPointwise };

struct Plan {
  OwnKernel kernel = OwnKernel::kNone;
  int k = 0, pad = 0;
  conv::Activation activation;
};

/// Wraps OpenCV's convolution layer: the wrapped layer is finalised and fused exactly as it
/// would be alone (and runs every case this one does not), while this one keeps its own copy of
/// the fused weights, computed with OpenCV's own operations in OpenCV's order.
class OwnConvLayer : public Layer {
 public:
  explicit OwnConvLayer(const cv::dnn::LayerParams& params)
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
    packed_weights_.clear();
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
    const Plan plan = ownPlan(inputs, outputs);
    if (plan.kernel == OwnKernel::kNone) {
      inner_->forward(inputs_arr, outputs_arr, internals_arr);
      return;
    }
    const cv::Mat& in = inputs[0];
    cv::Mat& out = outputs[0];
    if (plan.kernel == OwnKernel::kPointwise) {
      const int pixels = in.size[2] * in.size[3];
      if (packed_weights_.empty()) {
        conv::packPointwiseWeights(weights_.ptr<float>(), out.size[1], in.size[1], packed_weights_);
      }
      for (int n = 0; n < in.size[0]; ++n) {
        const conv::Pointwise job{in.ptr<float>(n),  in.size[1],  pixels,
                                  out.ptr<float>(n), out.size[1], packed_weights_.data(),
                                  bias_.data()};
        cv::parallel_for_(cv::Range(0, conv::pointwiseBlocks(pixels)), [&](const cv::Range& r) {
          std::vector<float> block;
          conv::pointwise(job, r.start, r.end, plan.activation, block);
        });
      }
      return;
    }
    const int channels = in.size[1], planes = in.size[0] * channels;
    cv::parallel_for_(cv::Range(0, planes), [&](const cv::Range& r) {
      std::vector<float> padded;
      for (int p = r.start; p < r.end; ++p) {
        const int n = p / channels, c = p % channels;
        const conv::DepthwisePlane job{in.ptr<float>(n, c),
                                       in.size[2],
                                       in.size[3],
                                       out.ptr<float>(n, c),
                                       out.size[2],
                                       out.size[3],
                                       weights_.ptr<float>(c),
                                       bias_[static_cast<std::size_t>(c)]};
        conv::depthwise(job, plan.k, plan.pad, plan.activation, padded);
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
    return ownPlan(in, out).kernel != OwnKernel::kNone;
  }

 private:
  // As OpenCV's ConvolutionLayerImpl::fuseWeights: (conv(I) + b1) * w + b2.
  void fuseWeights(const cv::Mat& w_in, const cv::Mat& b_in) {
    packed_weights_.clear();
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

  // Stride-1 depthwise 3 x 3 and 5 x 5 and 1 x 1 convolutions, no activation or a (leaky) ReLU.
  Plan ownPlan(const std::vector<cv::Mat>& inputs, const std::vector<cv::Mat>& outputs) const {
    if (!conv::cpuHasAvx2Fma() || inputs.size() != 1 || outputs.size() != 1 || blobs.empty() ||
        blobs[0].dims != 4) {
      return {};
    }
    const cv::Mat& in = inputs[0];
    const cv::Mat& out = outputs[0];
    if (in.dims != 4 || out.dims != 4 || in.type() != CV_32F || out.type() != CV_32F ||
        !in.isContinuous() || !out.isContinuous() || out.size[1] != blobs[0].size[0]) {
      return {};
    }
    const BaseConvolutionLayer& c = *inner_;
    if (c.kernel_size.size() != 2 || c.kernel_size[0] != c.kernel_size[1] ||
        c.strides != std::vector<std::size_t>{1, 1} ||
        c.dilations != std::vector<std::size_t>{1, 1} || c.pads_begin != c.pads_end ||
        c.pads_begin.size() != 2 || c.pads_begin[0] != c.pads_begin[1]) {
      return {};
    }
    Plan plan;
    plan.k = static_cast<int>(c.kernel_size[0]);
    plan.pad = static_cast<int>(c.pads_begin[0]);
    const int k = plan.k, pad = plan.pad;
    if (out.size[2] != in.size[2] + 2 * pad - k + 1 ||
        out.size[3] != in.size[3] + 2 * pad - k + 1) {
      return {};
    }
    const int cin = in.size[1];
    if (blobs[0].size[1] == 1 && cin == out.size[1] && (k == 3 || k == 5)) {
      plan.kernel = OwnKernel::kDepthwise;
    } else if (k == 1 && pad == 0 && blobs[0].size[1] == cin) {
      plan.kernel = OwnKernel::kPointwise;
    } else {
      return {};
    }
    const auto relu = activation_.dynamicCast<cv::dnn::ReLULayer>();
    if (!activation_.empty() && relu.empty()) return {};
    plan.activation = {!relu.empty(), relu.empty() ? 1.f : relu->negativeSlope};
    return plan;
  }

  cv::Ptr<BaseConvolutionLayer> inner_;
  cv::Ptr<ActivationLayer> activation_;
  cv::Mat weights_;                  // fused, out_cn x in_cn*k*k
  std::vector<double> multipliers_;  // as OpenCV's weightsMultipliers
  std::vector<float> bias_;
  std::vector<float> packed_weights_;  // 1 x 1: weights_ as the kernel reads them (1st forward)
};

std::mutex& registryMutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace

cv::Ptr<Layer> createConvolutionLayer(cv::dnn::LayerParams& params) {
  const int groups = params.get<int>("group", 1);
  const int outputs = params.get<int>("num_output", 0);
  const bool own = !params.blobs.empty() && params.blobs[0].dims == 4 &&
                   ((groups > 1 && groups == outputs && params.blobs[0].size[1] == 1) ||
                    (groups == 1 && params.blobs[0].size[2] == 1 && params.blobs[0].size[3] == 1));
  if (!own) return cv::dnn::ConvolutionLayer::create(params);
  return cv::makePtr<OwnConvLayer>(params);
}

bool isOwnConvLayer(const cv::Ptr<Layer>& layer) {
  return !layer.dynamicCast<OwnConvLayer>().empty();
}

bool runsOwnConvKernel(const cv::Ptr<Layer>& layer, const MatShape& input) {
  const auto own = layer.dynamicCast<OwnConvLayer>();
  return !own.empty() && own->runsOwnKernel(input);
}

ScopedOwnConvLayers::ScopedOwnConvLayers() : lock_(registryMutex()) {
  cv::dnn::LayerFactory::registerLayer("Convolution", &createConvolutionLayer);
}

ScopedOwnConvLayers::~ScopedOwnConvLayers() {
  cv::dnn::LayerFactory::unregisterLayer("Convolution");
}

}  // namespace dynamap
