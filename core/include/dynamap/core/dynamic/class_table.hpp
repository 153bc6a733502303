#pragma once

#include <string>
#include <vector>

#include "dynamap/core/dynamic_config.hpp"

namespace dynamap {

/// The 80 COCO classes with a motion prior each. High-dynamic classes (people, animals,
/// vehicles) move by themselves; low-dynamic ones (chairs, cups) only when carried. One more
/// class, kMover ("mover"), is no detector's: a region that geometry alone found moving (a pushed
/// box or chair), high-dynamic, so that keeping it takes evidence that it stands still.
class ClassTable {
 public:
  static constexpr int kMover = 80;  ///< class id of a mover found by geometry (one past COCO's)

  /// Throws std::invalid_argument naming an unknown class name or a bad weight.
  explicit ClassTable(const DynamicConfig& config);

  static const std::vector<std::string>& cocoNames();
  /// -1 for an unknown name.
  static int classIndex(const std::string& name);

  std::size_t size() const { return weights_.size(); }  ///< COCO's 80 and kMover
  const std::string& name(int class_id) const;
  bool isHighDynamic(int class_id) const;
  /// A high-dynamic class the detector reports (a person, an animal: it moves by itself, and may
  /// sway or step on the spot), not a mover that geometry found.
  bool isDetectedHighDynamic(int class_id) const {
    return class_id != kMover && isHighDynamic(class_id);
  }
  /// Motion prior in [0, 1]; 0 for an out-of-range id.
  double weight(int class_id) const;
  /// Score threshold the detector applies to this class.
  float scoreThreshold(int class_id) const;
  std::vector<float> scoreThresholds() const;

 private:
  std::vector<double> weights_;
  std::vector<bool> high_dynamic_;
  std::vector<float> thresholds_;
};

}  // namespace dynamap
