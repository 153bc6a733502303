#pragma once

namespace dynamap {

/// Tracking front-end parameters. Defaults live here; tools/ binds them to YAML keys
/// "tracking.<name>" (tools/io/config_bind_tracking.cpp).
struct TrackerConfig {
  int orb_features = 1000;   ///< ORB keypoints extracted per (key)frame
  int lk_levels = 6;         ///< pyramid levels of Lucas-Kanade optical flow
  double lk_scale = 0.5;     ///< scale between pyramid levels
  double depth_min_m = 0.1;  ///< depth readings outside [min, max] are ignored
  double depth_max_m = 6.0;
  bool bundle_adjustment = true;  ///< local BA on its own thread
};

}  // namespace dynamap
