#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>

#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>

#include "dynamap/core/dynamic/object_detector.hpp"
#ifdef DYNAMAP_HAVE_FAST_CONV
#include "dynamap/fast_paths/own_conv_layers.hpp"
#endif

namespace dynamap {

namespace {

constexpr int kNumClasses = 80;

void requireFile(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (path.empty()) throw DetectorError("detector: no " + what + " file given");
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw DetectorError("detector: " + what + " file not found: " + path);
  }
}

std::vector<cv::Mat> runNet(cv::dnn::Net& net, const cv::Mat& blob) {
  net.setInput(blob);
  std::vector<cv::Mat> outs;
  net.forward(outs, net.getUnconnectedOutLayersNames());
  return outs;
}

/// Shape of a blob as rows x cols of its trailing two dimensions (leading 1s dropped).
std::pair<int, int> trailing2d(const cv::Mat& m) {
  if (m.dims == 2) return {m.rows, m.cols};
  if (m.dims == 3 && m.size[0] == 1) return {m.size[1], m.size[2]};
  return {-1, -1};
}

/// Base: owns the net, checks the layout once at construction with a grey image.
class NetDetector : public ObjectDetector {
 public:
  std::vector<Detection> detect(const cv::Mat& bgr) override {
    return suppressDuplicates(candidates(bgr), options_.nms);
  }

 protected:
  explicit NetDetector(DetectorOptions options) : options_(std::move(options)) {}
  /// Reads the net, runs `check` on it (may throw), then probes it with a grey image.
  void load(const std::function<cv::dnn::Net()>& reader, const std::string& file,
            const std::function<void()>& check = {}) {
    try {
      net_ = reader();
    } catch (const cv::Exception& e) {
      throw DetectorError("detector: cannot read model " + file + ": " + e.what());
    }
    if (net_.empty()) throw DetectorError("detector: cannot read model " + file);
    if (check) check();
    net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
    net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
    try {
      const cv::Mat probe(options_.input_height, options_.input_width, CV_8UC3,
                          cv::Scalar::all(114));
      const std::string problem = checkLayout(runNet(net_, blob(probe)));
      if (!problem.empty()) throw DetectorError("detector: model " + file + ": " + problem);
    } catch (const cv::Exception& e) {
      throw DetectorError("detector: model " + file + " fails on a test input: " + e.what());
    }
  }
  virtual cv::Mat blob(const cv::Mat& bgr) = 0;
  virtual std::string checkLayout(const std::vector<cv::Mat>& outs) const = 0;
  virtual std::vector<Detection> candidates(const cv::Mat& bgr) = 0;

  DetectorOptions options_;
  cv::dnn::Net net_;
  Letterbox geometry_;
};

class DarknetDetector : public NetDetector {
 public:
  explicit DarknetDetector(const DetectorOptions& o) : NetDetector(o) {
    requireFile(o.model_cfg, "Darknet cfg");
    requireFile(o.model_weights, "Darknet weights");
    // The size check comes before the probe: a net with uninitialised weights is never run.
    // With the fast paths, its layers are made while the faster convolutions are registered
    // (core/fast_paths/own_conv_layers.cpp: the same outputs to float rounding).
    load(
        [&] {
#ifdef DYNAMAP_HAVE_FAST_CONV
          ScopedOwnConvLayers own_convolutions;
#endif
          cv::dnn::Net net = cv::dnn::readNetFromDarknet(o.model_cfg, o.model_weights);
          for (const auto& name : net.getLayerNames()) net.getLayer(net.getLayerId(name));
          return net;
        },
        o.model_cfg + " / " + o.model_weights, [&] { checkWeightsSize(o.model_weights); });
  }

 protected:
  cv::Mat blob(const cv::Mat& bgr) override {
    return cv::dnn::blobFromImage(bgr, 1.0 / 255.0, {options_.input_width, options_.input_height},
                                  {}, true, false);
  }
  std::string checkLayout(const std::vector<cv::Mat>& outs) const override {
    for (const auto& o : outs) {
      if (trailing2d(o).second != 5 + kNumClasses) return "expected N x 85 region outputs";
    }
    return outs.empty() ? "no outputs" : "";
  }
  /// OpenCV's Darknet reader does not check for short reads: a truncated .weights file loads
  /// and leaves part of the network uninitialised. The file must hold the header and one float
  /// per parameter of the convolution and batch-norm layers (Region layers' anchors come from
  /// the cfg).
  void checkWeightsSize(const std::string& path) {
    std::uintmax_t params = 0;
    for (const auto& name : net_.getLayerNames()) {
      const auto layer = net_.getLayer(net_.getLayerId(name));
      if (layer->type == "Region") continue;
      for (const auto& b : layer->blobs) params += b.total();
    }
    std::ifstream in(path, std::ios::binary);
    std::int32_t version[3] = {0, 0, 0};
    in.read(reinterpret_cast<char*>(version), sizeof(version));
    const bool long_seen =
        version[0] * 10 + version[1] >= 2 && version[0] < 1000 && version[1] < 1000;
    const std::uintmax_t expected = sizeof(version) + (long_seen ? 8 : 4) + 4 * params;
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec || size < expected) {
      throw DetectorError("detector: Darknet weights file " + path +
                          " is truncated: " + std::to_string(ec ? 0 : size) +
                          " bytes, the cfg needs " + std::to_string(expected));
    }
  }
  std::vector<Detection> candidates(const cv::Mat& bgr) override {
    std::vector<Detection> all;
    for (const auto& o : runNet(net_, blob(bgr))) {
      auto d = decodeDarknet(o, bgr.size(), minCandidateScore(options_.nms));
      all.insert(all.end(), d.begin(), d.end());
    }
    return all;
  }
};

/// YOLOv5 (1 x N x 85) and YOLOv8 (1 x 84 x N) ONNX exports, letterboxed input.
class YoloOnnxDetector : public NetDetector {
 public:
  YoloOnnxDetector(const DetectorOptions& o, bool v8) : NetDetector(o), v8_(v8) {
    requireFile(o.model_weights, "ONNX model");
    load([&] { return cv::dnn::readNetFromONNX(o.model_weights); }, o.model_weights);
  }

 protected:
  cv::Mat blob(const cv::Mat& bgr) override {
    const cv::Mat lb = letterboxImage(bgr, options_.input_width, options_.input_height, &geometry_);
    return cv::dnn::blobFromImage(lb, 1.0 / 255.0, lb.size(), {}, true, false);
  }
  std::string checkLayout(const std::vector<cv::Mat>& outs) const override {
    if (outs.size() != 1) return "expected exactly one output";
    const auto [a, b] = trailing2d(outs[0]);
    if (!v8_ && b != 5 + kNumClasses) return "expected a YOLOv5 output 1 x N x 85";
    if (v8_ && a != 4 + kNumClasses) return "expected a YOLOv8 output 1 x 84 x N";
    return "";
  }
  std::vector<Detection> candidates(const cv::Mat& bgr) override {
    const auto outs = runNet(net_, blob(bgr));
    const float min_score = minCandidateScore(options_.nms);
    return v8_ ? decodeYoloV8(outs[0], geometry_, min_score)
               : decodeYoloV5(outs[0], geometry_, min_score);
  }

 private:
  bool v8_;
};

/// NanoDet-m: three strides, class maps (cells x 80) and distribution box maps (cells x 32).
class NanoDetDetector : public NetDetector {
 public:
  explicit NanoDetDetector(const DetectorOptions& o) : NetDetector(o) {
    requireFile(o.model_weights, "ONNX model");
    load([&] { return cv::dnn::readNetFromONNX(o.model_weights); }, o.model_weights);
  }

 protected:
  cv::Mat blob(const cv::Mat& bgr) override {
    cv::Mat b = cv::dnn::blobFromImage(bgr, 1.0, {options_.input_width, options_.input_height},
                                       cv::Scalar(103.53, 116.28, 123.675), false, false);
    const double inv_std[3] = {1.0 / 57.375, 1.0 / 57.12, 1.0 / 58.395};
    const int plane = options_.input_width * options_.input_height;
    for (int c = 0; c < 3; ++c) {
      cv::Mat ch(1, plane, CV_32F, b.ptr<float>(0, c));
      ch *= inv_std[c];
    }
    return b;
  }
  std::string checkLayout(const std::vector<cv::Mat>& outs) const override {
    for (int stride : {8, 16, 32}) {
      if (find(outs, stride, kNumClasses) < 0 || find(outs, stride, 32) < 0) {
        return "expected class (cells x 80) and box (cells x 32) maps for strides 8, 16, 32";
      }
    }
    return "";
  }
  std::vector<Detection> candidates(const cv::Mat& bgr) override;

 private:
  int gridWidth(int stride) const { return (options_.input_width + stride - 1) / stride; }
  int cells(int stride) const {
    return gridWidth(stride) * ((options_.input_height + stride - 1) / stride);
  }
  int find(const std::vector<cv::Mat>& outs, int stride, int channels) const {
    for (std::size_t i = 0; i < outs.size(); ++i) {
      const auto [r, c] = trailing2d(outs[i]);
      if (r == cells(stride) && c == channels) return static_cast<int>(i);
    }
    return -1;
  }
};

float expectedDistance(const float* bins) {
  float mx = bins[0];
  for (int k = 1; k < 8; ++k) mx = std::max(mx, bins[k]);
  float sum = 0.f, acc = 0.f;
  for (int k = 0; k < 8; ++k) {
    const float e = std::exp(bins[k] - mx);
    sum += e;
    acc += e * static_cast<float>(k);
  }
  return acc / sum;
}

std::vector<Detection> NanoDetDetector::candidates(const cv::Mat& bgr) {
  const auto outs = runNet(net_, blob(bgr));
  const float min_score = minCandidateScore(options_.nms);
  const float sx = static_cast<float>(bgr.cols) / options_.input_width;
  const float sy = static_cast<float>(bgr.rows) / options_.input_height;
  std::vector<Detection> all;
  for (int stride : {8, 16, 32}) {
    const cv::Mat& cls = outs[find(outs, stride, kNumClasses)];
    const cv::Mat& box = outs[find(outs, stride, 32)];
    const float* cp = cls.ptr<float>();
    const float* bp = box.ptr<float>();
    for (int i = 0; i < cells(stride); ++i) {
      const float* scores = cp + static_cast<std::size_t>(i) * kNumClasses;
      const float cx = (i % gridWidth(stride)) * stride + 0.5f * (stride - 1);
      const float cy = (i / gridWidth(stride)) * stride + 0.5f * (stride - 1);
      float d[4] = {0, 0, 0, 0};
      bool decoded = false;
      for (int c = 0; c < kNumClasses; ++c) {
        if (scores[c] < min_score) continue;
        if (!decoded) {
          for (int s = 0; s < 4; ++s) d[s] = expectedDistance(bp + i * 32 + s * 8) * stride;
          decoded = true;
        }
        const float x0 = (cx - d[0]) * sx, y0 = (cy - d[1]) * sy;
        all.push_back(
            {cv::Rect2f(x0, y0, (cx + d[2]) * sx - x0, (cy + d[3]) * sy - y0), c, scores[c]});
      }
    }
  }
  return all;
}

}  // namespace

int defaultInputSize(const std::string& kind) {
  if (kind == "yolo_darknet") return 256;
  if (kind == "nanodet_onnx") return 320;
  if (kind == "yolov5_onnx" || kind == "yolov8_onnx") return 640;
  return 0;
}

std::unique_ptr<ObjectDetector> makeObjectDetector(const DetectorOptions& options,
                                                   const ClassTable& class_table) {
  DetectorOptions o = options;
  if (o.input_width <= 0) o.input_width = defaultInputSize(o.kind);
  if (o.input_height <= 0) o.input_height = defaultInputSize(o.kind);
  o.nms.class_score_threshold = class_table.scoreThresholds();
  if (o.kind == "yolo_darknet") return std::make_unique<DarknetDetector>(o);
  if (o.kind == "yolov5_onnx") return std::make_unique<YoloOnnxDetector>(o, false);
  if (o.kind == "yolov8_onnx") return std::make_unique<YoloOnnxDetector>(o, true);
  if (o.kind == "nanodet_onnx") return std::make_unique<NanoDetDetector>(o);
  throw DetectorError("detector: unknown kind '" + o.kind +
                      "' (known: yolo_darknet, yolov5_onnx, yolov8_onnx, nanodet_onnx)");
}

}  // namespace dynamap
