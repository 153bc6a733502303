#include "app_config.hpp"

namespace dynamap {

void bindTrackingConfig(ConfigSchema& schema, TrackerConfig& c) {
  schema.addInt("tracking.orb_features", &c.orb_features, 50, 20000);
  schema.addInt("tracking.lk_levels", &c.lk_levels, 1, 10);
  schema.addDouble("tracking.lk_scale", &c.lk_scale, 0.5, 0.5);  // OpenCV's LK pyramid is fixed 0.5
  schema.addDouble("tracking.depth_min_m", &c.depth_min_m, 0.0, 100.0);
  schema.addDouble("tracking.depth_max_m", &c.depth_max_m, 0.0, 100.0);
  schema.addBool("tracking.bundle_adjustment", &c.bundle_adjustment);
}

}  // namespace dynamap
