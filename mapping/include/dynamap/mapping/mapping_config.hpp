#pragma once

#include <map>
#include <string>

#include "dynamap/mapping/static_points.hpp"

namespace dynamap {

/// Dense-mapping parameters, bound to YAML keys "mapping.<name>"
/// (tools/io/config_bind_mapping.cpp). Backend parameters are free-form under
/// "mapping.params.<backend>.<key>" and validated by the backend itself.
struct MappingConfig {
  std::string backend = "pcl_voxel";
  std::map<std::string, std::string> params;  ///< "<backend>.<key>" -> value
  /// Depth + dynamic mask -> static points ("mapping.depth_min_m", "mapping.mask_dilation_px",
  /// ...).
  StaticPointsOptions static_points;
  /// A keyframe waits for this many frames; whatever their dynamic masks cover of its surfaces
  /// is masked in it too (maskSeenLater): a person the detector finds a moment later was there
  /// already. 0 = a keyframe goes to the mapper at once.
  int mask_lookahead_frames = 2;
  /// A keyframe's mask, once complete, keeps its margin (dynamic.mask_dilation_px) off pixels
  /// more than this (m) behind the masked depth next to them (marginNotBehind()). 0 = as it is.
  double mask_margin_behind_m = 0.1;
};

}  // namespace dynamap
