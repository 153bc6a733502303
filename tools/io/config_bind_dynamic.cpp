#include "app_config.hpp"

namespace dynamap {

void bindDynamicConfig(ConfigSchema& schema, DynamicConfig& c) {
  schema.addString("dynamic.mode", &c.mode, {"off", "geometry", "detector", "both"});
  schema.addDouble("dynamic.epipolar_threshold_px", &c.epipolar_threshold_px, 0.01, 100.0);
}

}  // namespace dynamap
