#include "dynamap/core/dynamic/class_table.hpp"

#include <stdexcept>

namespace dynamap {

namespace {

double parseWeight(const std::string& name, const std::string& text) {
  std::size_t used = 0;
  double w = -1.0;
  try {
    w = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || w < 0.0 || w > 1.0) {
    throw std::invalid_argument("dynamic.class_weights." + name + ": '" + text +
                                "' is not a number in [0, 1]");
  }
  return w;
}

}  // namespace

const std::vector<std::string>& ClassTable::cocoNames() {
  static const std::vector<std::string> kNames{"person",        "bicycle",      "car",
                                               "motorcycle",    "airplane",     "bus",
                                               "train",         "truck",        "boat",
                                               "traffic light", "fire hydrant", "stop sign",
                                               "parking meter", "bench",        "bird",
                                               "cat",           "dog",          "horse",
                                               "sheep",         "cow",          "elephant",
                                               "bear",          "zebra",        "giraffe",
                                               "backpack",      "umbrella",     "handbag",
                                               "tie",           "suitcase",     "frisbee",
                                               "skis",          "snowboard",    "sports ball",
                                               "kite",          "baseball bat", "baseball glove",
                                               "skateboard",    "surfboard",    "tennis racket",
                                               "bottle",        "wine glass",   "cup",
                                               "fork",          "knife",        "spoon",
                                               "bowl",          "banana",       "apple",
                                               "sandwich",      "orange",       "broccoli",
                                               "carrot",        "hot dog",      "pizza",
                                               "donut",         "cake",         "chair",
                                               "couch",         "potted plant", "bed",
                                               "dining table",  "toilet",       "tv",
                                               "laptop",        "mouse",        "remote",
                                               "keyboard",      "cell phone",   "microwave",
                                               "oven",          "toaster",      "sink",
                                               "refrigerator",  "book",         "clock",
                                               "vase",          "scissors",     "teddy bear",
                                               "hair drier",    "toothbrush"};
  return kNames;
}

int ClassTable::classIndex(const std::string& name) {
  const auto& names = cocoNames();
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return static_cast<int>(i);
  }
  return -1;
}

ClassTable::ClassTable(const DynamicConfig& config) {
  const std::size_t n = cocoNames().size();
  weights_.assign(n, config.low_dynamic_weight);
  high_dynamic_.assign(n, false);
  thresholds_.assign(n, static_cast<float>(config.score_threshold));
  for (const auto& name : config.high_dynamic_classes) {
    const int id = classIndex(name);
    if (id < 0)
      throw std::invalid_argument("dynamic.high_dynamic_classes: unknown class '" + name + "'");
    high_dynamic_[id] = true;
    weights_[id] = config.high_dynamic_weight;
    thresholds_[id] = static_cast<float>(config.high_dynamic_score_threshold);
  }
  for (const auto& [name, text] : config.class_weights) {
    const int id = classIndex(name);
    if (id < 0) throw std::invalid_argument("dynamic.class_weights: unknown class '" + name + "'");
    weights_[id] = parseWeight(name, text);
  }
  weights_.push_back(config.high_dynamic_weight);  // kMover; the detector never reports it
  high_dynamic_.push_back(true);
}

const std::string& ClassTable::name(int class_id) const {
  static const std::string kUnknown = "unknown", kMoverName = "mover";
  if (class_id == kMover) return kMoverName;
  if (class_id < 0 || class_id >= static_cast<int>(weights_.size())) return kUnknown;
  return cocoNames()[class_id];
}

bool ClassTable::isHighDynamic(int class_id) const {
  return class_id >= 0 && class_id < static_cast<int>(weights_.size()) && high_dynamic_[class_id];
}

double ClassTable::weight(int class_id) const {
  if (class_id < 0 || class_id >= static_cast<int>(weights_.size())) return 0.0;
  return weights_[class_id];
}

float ClassTable::scoreThreshold(int class_id) const {
  if (class_id < 0 || class_id >= static_cast<int>(thresholds_.size())) return 1.f;
  return thresholds_[class_id];
}

std::vector<float> ClassTable::scoreThresholds() const { return thresholds_; }

}  // namespace dynamap
