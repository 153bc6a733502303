#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/dynamic/class_table.hpp"
#include "dynamap/core/dynamic/nms.hpp"

namespace dynamap {

/// A model file is missing, unreadable or has an unexpected layout. Thrown at construction;
/// the message names the file.
class DetectorError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Which network and how to run it.
struct DetectorOptions {
  std::string kind = "yolo_darknet";  ///< yolo_darknet | yolov5_onnx | yolov8_onnx | nanodet_onnx
  std::string model_cfg;              ///< Darknet .cfg (unused for ONNX)
  std::string model_weights;          ///< Darknet .weights or .onnx
  int input_width = 0;                ///< network input; 0 = defaultInputSize(kind)
  int input_height = 0;               ///< network input; 0 = defaultInputSize(kind)
  NmsOptions nms;
};

/// Detects COCO objects in a colour image. detect() is not thread-safe (one caller at a time).
class ObjectDetector {
 public:
  virtual ~ObjectDetector() = default;
  /// Final detections (after NMS) in image pixels.
  virtual std::vector<Detection> detect(const cv::Mat& bgr) = 0;
};

/// The square input a kind of detector runs at when none is given: yolo_darknet (Yolo-Fastest)
/// 256, measured as accurate as 320 for people at 2/3 of the cost (BENCHMARKS.md, "Detector
/// input"); nanodet_onnx 320 (its export is fixed at that size); yolov5_onnx / yolov8_onnx 640
/// (their usual export). 0 for an unknown kind.
int defaultInputSize(const std::string& kind);

/// Builds the detector; throws DetectorError (naming the file) for a missing file, a file
/// OpenCV cannot read, or a network whose outputs do not have the expected layout.
/// `class_table` gives the per-class score thresholds used by NMS.
std::unique_ptr<ObjectDetector> makeObjectDetector(const DetectorOptions& options,
                                                   const ClassTable& class_table);

/// Letterbox geometry: input = resize(image, scale) placed at (pad_x, pad_y).
struct Letterbox {
  double scale = 1.0;
  double pad_x = 0.0;
  double pad_y = 0.0;
};
/// Letterboxes `bgr` into a width x height canvas (grey 114), like YOLOv5/v8 exports expect.
cv::Mat letterboxImage(const cv::Mat& bgr, int width, int height, Letterbox* geometry);

/// Candidate boxes (before NMS) from a YOLOv5 output 1 x N x (5 + C): cx, cy, w, h in input
/// pixels, objectness, class probabilities. Keeps class scores >= `min_score`.
std::vector<Detection> decodeYoloV5(const cv::Mat& output, const Letterbox& geometry,
                                    float min_score);
/// Candidate boxes from a YOLOv8 output 1 x (4 + C) x N (no objectness).
std::vector<Detection> decodeYoloV8(const cv::Mat& output, const Letterbox& geometry,
                                    float min_score);
/// Candidate boxes from Darknet region outputs N x (5 + C) with normalised boxes and class
/// scores already multiplied by the objectness.
std::vector<Detection> decodeDarknet(const cv::Mat& output, const cv::Size& image_size,
                                     float min_score);

}  // namespace dynamap
