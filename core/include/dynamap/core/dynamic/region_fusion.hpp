#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/dynamic/class_table.hpp"
#include "dynamap/core/dynamic/nms.hpp"
#include "dynamap/core/dynamic_config.hpp"

namespace dynamap {

enum class FusionMode : std::uint8_t {
  kGeometry,  ///< dynamic-point clusters grown on depth only
  kDetector,  ///< every high-dynamic box, cut by depth (naive baseline, no motion check)
  kBoth,      ///< boxes decided moving by their dynamic points + clusters outside boxes
};

/// What fusion decided about one detection in the current frame.
struct ObjectDecision {
  Detection detection;
  double weight = 0.0;      ///< class motion prior
  int points = 0;           ///< tracked points on the object's own pixels
  int dynamic_points = 0;   ///< of which dynamic
  bool moving_now = false;  ///< evidence in this frame
  bool moving = false;      ///< after hysteresis (what is masked)
  double depth_m = 0.0;     ///< depth mode of the object (0 = no depth)
};

struct FusionResult {
  cv::Mat mask;            ///< CV_8UC1, 255 = moving
  cv::Mat static_objects;  ///< CV_8UC1, 255 = pixels of detected objects decided not moving
  std::vector<ObjectDecision> objects;
  int clusters = 0;  ///< dynamic-point clusters grown into regions outside objects
};

/// The object's own pixels inside `box`: pixels within `band_m` of the dominant depth mode of
/// the box centre, largest connected component, holes closed. Empty Mat if no depth.
/// Returns a full-image CV_8UC1 mask (255 = object) and the mode in *depth_mode_m.
cv::Mat objectPixels(const cv::Mat& depth_m, const cv::Rect& box, double band_m,
                     double* depth_mode_m);

/// Fuses dynamic points and detections into a motion mask, with per-object temporal hysteresis
/// (objects are associated frame to frame by box IoU). fuse() with `evidence_valid` = false (the
/// point flags carry no information: degenerate geometric check): objects keep their state and
/// no clusters are grown. Not thread-safe (one caller).
class RegionFusion {
 public:
  RegionFusion(const DynamicConfig& config, const ClassTable& classes);

  FusionResult fuse(FusionMode mode, const cv::Mat& depth_m, const std::vector<cv::Point2f>& points,
                    const std::vector<std::uint8_t>& point_is_dynamic,
                    const std::vector<Detection>& detections, bool evidence_valid = true);

 private:
  struct Track {
    cv::Rect2f box;
    int class_id = -1;
    double score = 0.0;  ///< smoothed motion evidence
    bool moving = false;
  };
  void decideObject(ObjectDecision& d, std::vector<Track>& next);
  int growClusters(const cv::Mat& depth_m, const std::vector<cv::Point2f>& points,
                   const std::vector<std::uint8_t>& dyn, const cv::Mat& claimed,
                   cv::Mat& mask) const;

  DynamicConfig config_;
  ClassTable classes_;
  std::vector<Track> tracks_;
  bool evidence_valid_ = true;
};

}  // namespace dynamap
