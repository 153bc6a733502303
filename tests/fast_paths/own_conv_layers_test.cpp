// The detector's own convolution layers exist with OpenCV < 4.7 only (core/fast_paths).
#ifdef DYNAMAP_HAVE_FAST_CONV
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core/utility.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgcodecs.hpp>

#include "dynamap/fast_paths/own_conv_layers.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

namespace fs = std::filesystem;

/// Values of two float blobs that differ by more than float rounding of a sum of a few hundred
/// products: 1e-4 relative to the value's size (1e-4 absolute near zero).
std::size_t differingValues(const cv::Mat& a, const cv::Mat& b) {
  if (a.total() != b.total() || a.type() != b.type()) return std::max(a.total(), b.total());
  std::size_t n = 0;
  const float* pa = a.ptr<float>();
  const float* pb = b.ptr<float>();
  for (std::size_t i = 0; i < a.total(); ++i) {
    n += !(std::fabs(pa[i] - pb[i]) <= 1e-4f * (1.f + std::fabs(pa[i])));
  }
  return n;
}

cv::Mat randomBlob(const std::vector<int>& shape, cv::RNG& rng) {
  cv::Mat m(shape, CV_32F);
  rng.fill(m, cv::RNG::NORMAL, 0.0, 1.0);
  float* p = m.ptr<float>();
  for (std::size_t i = 0; i < m.total(); i += 7) p[i] = (i % 2) ? 0.f : -0.f;  // signed zeros
  return m;
}

struct Case {
  int kernel;        ///< 1: a 1 x 1 convolution of in_channels; else depthwise
  int in_channels;   ///< = output channels for depthwise
  int out_channels;  ///< 1 x 1 only
  int size;          ///< square input plane
  bool batch_norm, leaky_relu, own_kernel;
  std::string name() const {
    return (kernel == 1 ? "1x1 " + std::to_string(in_channels) + "->" + std::to_string(out_channels)
                        : "depthwise " + std::to_string(kernel) + "x" + std::to_string(kernel)) +
           " on " + std::to_string(size) + "x" + std::to_string(size);
  }
};

/// conv (random weights) [-> batch norm] [-> leaky ReLU], as the Darknet reader builds
/// Yolo-Fastest's layers; OpenCV fuses the batch norm and the ReLU into the conv.
cv::dnn::Net makeNet(const Case& c, std::uint64_t seed) {
  cv::RNG rng(seed);
  const bool depthwise = c.kernel > 1;
  const int out = depthwise ? c.in_channels : c.out_channels;
  cv::dnn::Net net;
  cv::dnn::LayerParams conv;
  conv.set("kernel_size", c.kernel);
  conv.set("pad", c.kernel / 2);
  conv.set("stride", 1);
  conv.set("num_output", out);
  conv.set("group", depthwise ? c.in_channels : 1);
  conv.set("bias_term", !c.batch_norm);
  conv.blobs.push_back(randomBlob({out, depthwise ? 1 : c.in_channels, c.kernel, c.kernel}, rng));
  if (!c.batch_norm) conv.blobs.push_back(randomBlob({out}, rng));
  net.addLayerToPrev("conv", "Convolution", conv);
  if (c.batch_norm) {
    cv::dnn::LayerParams bn;
    bn.set("has_weight", true);
    bn.set("has_bias", true);
    bn.set("eps", 1e-5);
    cv::Mat var = cv::abs(randomBlob({1, out}, rng)) + 0.1;
    bn.blobs = {randomBlob({1, out}, rng), var, randomBlob({1, out}, rng),
                randomBlob({1, out}, rng)};
    net.addLayerToPrev("bn", "BatchNorm", bn);
  }
  if (c.leaky_relu) {
    cv::dnn::LayerParams relu;
    relu.set("negative_slope", 0.1f);
    net.addLayerToPrev("relu", "ReLU", relu);
  }
  net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  return net;
}

void expectSameValues(const Case& c) {
  SCOPED_TRACE(c.name());
  cv::dnn::Net plain = makeNet(c, 7), own;
  {
    ScopedOwnConvLayers scope;
    own = makeNet(c, 7);
    own.getLayer(own.getLayerId("conv"));
  }
  cv::RNG rng(11);
  const cv::dnn::MatShape shape{2, c.in_channels, c.size, c.size};
  const cv::Mat input = randomBlob(shape, rng);
  plain.setInput(input);
  own.setInput(input);
  const cv::Mat expected = plain.forward().clone();
  const cv::Mat got = own.forward().clone();
  EXPECT_EQ(differingValues(expected, got), 0u) << "of " << expected.total();
  const auto layer = own.getLayer(own.getLayerId("conv"));
  EXPECT_TRUE(isOwnConvLayer(layer));
  EXPECT_EQ(runsOwnConvKernel(layer, shape), c.own_kernel);
  EXPECT_FALSE(isOwnConvLayer(plain.getLayer(plain.getLayerId("conv"))));
}

TEST(OwnConvLayers, DepthwiseSameValuesAsOpenCvOnEveryPath) {
  if (!cv::checkHardwareSupport(CV_CPU_AVX2) || !cv::checkHardwareSupport(CV_CPU_FMA3)) {
    GTEST_SKIP() << "no AVX2 + FMA: the layer always runs OpenCV's";
  }
  // Planes of whole and partial vectors (and rows of 4, 1-3 vectors), OpenCV's fast depthwise
  // path (3 x 3, >= 18 px wide) and its generic one alike.
  const Case cases[] = {{3, 19, 0, 8, true, true, true},   {3, 19, 0, 16, true, true, true},
                        {3, 19, 0, 11, true, false, true}, {3, 19, 0, 13, false, true, true},
                        {3, 19, 0, 17, true, true, true},  {3, 19, 0, 24, true, true, true},
                        {3, 5, 0, 45, true, true, true},   {5, 19, 0, 16, true, true, true},
                        {5, 19, 0, 9, false, false, true}, {5, 7, 0, 37, true, true, true}};
  for (const Case& c : cases) expectSameValues(c);
}

TEST(OwnConvLayers, PointwiseSameValuesAsOpenCvOnEveryPath) {
  if (!cv::checkHardwareSupport(CV_CPU_AVX2) || !cv::checkHardwareSupport(CV_CPU_FMA3)) {
    GTEST_SKIP() << "no AVX2 + FMA: the layer always runs OpenCV's";
  }
  // Output channels in whole blocks of 6 and not (1-5 left); planes of whole blocks of 16
  // pixels and a partial last one (1, 4, 9 or 15 pixels), 1 to 520 input channels.
  const Case cases[] = {{1, 8, 12, 16, true, true, true},   {1, 16, 48, 8, true, false, true},
                        {1, 24, 8, 9, false, true, true},   {1, 32, 20, 16, true, true, true},
                        {1, 45, 13, 10, true, true, true},  {1, 144, 33, 8, true, false, true},
                        {1, 272, 7, 16, false, true, true}, {1, 40, 9, 17, true, true, true},
                        {1, 520, 5, 8, true, true, true},   {1, 1, 7, 5, true, true, true},
                        {1, 3, 1, 7, false, false, true}};
  for (const Case& c : cases) expectSameValues(c);
}

TEST(OwnConvLayers, OutsideTheirScopeConvolutionsAreOpenCvsAgain) {
  { ScopedOwnConvLayers scope; }
  cv::dnn::Net net = makeNet({3, 4, 0, 8, true, true, true}, 3);
  EXPECT_FALSE(isOwnConvLayer(net.getLayer(net.getLayerId("conv"))));
}

TEST(OwnConvLayers, YoloFastestGivesTheSameValuesOnRealFrames) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const fs::path dir = test::sharedModels() / "yolo-fastest";
  const std::string cfg = (dir / "yolo-fastest-1.1-xl.cfg").string();
  const std::string weights = (dir / "yolo-fastest-1.1-xl.weights").string();
  if (!fs::exists(weights)) GTEST_SKIP() << weights << " not found";
  cv::dnn::Net plain = cv::dnn::readNetFromDarknet(cfg, weights), own;
  {
    ScopedOwnConvLayers scope;
    own = cv::dnn::readNetFromDarknet(cfg, weights);
    for (const auto& name : own.getLayerNames()) own.getLayer(own.getLayerId(name));
  }
  std::vector<fs::path> frames;
  for (const auto& e :
       fs::directory_iterator(test::sharedData() / "dynamic/teddy_dyn_crowd_dev/rgb")) {
    frames.push_back(e.path());
  }
  std::sort(frames.begin(), frames.end());
  ASSERT_GE(frames.size(), 121u);
  const auto names = plain.getUnconnectedOutLayersNames();
  for (const std::size_t i : {std::size_t{0}, std::size_t{60}, std::size_t{120}}) {
    const cv::Mat blob = cv::dnn::blobFromImage(cv::imread(frames[i].string()), 1.0 / 255.0,
                                                {256, 256}, {}, true, false);
    std::vector<cv::Mat> expected, got;
    plain.setInput(blob);
    plain.forward(expected, names);
    own.setInput(blob);
    own.forward(got, names);
    ASSERT_EQ(expected.size(), got.size());
    for (std::size_t k = 0; k < expected.size(); ++k) {
      EXPECT_EQ(differingValues(expected[k], got[k]), 0u) << frames[i] << " output " << k;
    }
  }
  // At 256 x 256 its 55 1 x 1 layers and its stride-1 depthwise ones take the own kernels (the
  // first 3 x 3 convolution and the stride-2 depthwise ones stay OpenCV's).
  std::vector<int> ids;
  std::vector<std::vector<cv::dnn::MatShape>> in_shapes, out_shapes;
  own.getLayersShapes(cv::dnn::MatShape{1, 3, 256, 256}, ids, in_shapes, out_shapes);
  int own_kernels = 0;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (!in_shapes[i].empty())
      own_kernels += runsOwnConvKernel(own.getLayer(ids[i]), in_shapes[i][0]);
  }
  EXPECT_GE(own_kernels, 70);
}

}  // namespace
}  // namespace dynamap

#endif  // DYNAMAP_HAVE_FAST_CONV
