#include "app_config.hpp"

namespace dynamap {

void bindMappingConfig(ConfigSchema& schema, MappingConfig& c) {
  schema.addString("mapping.backend", &c.backend);
  schema.addStringMap("mapping.params", &c.params);
  StaticPointsOptions& s = c.static_points;
  schema.addDouble("mapping.depth_min_m", &s.depth_min_m, 0.0, 100.0);
  schema.addDouble("mapping.depth_max_m", &s.depth_max_m, 0.0, 100.0);
  schema.addInt("mapping.mask_dilation_px", &s.mask_dilation_px, 0, 100);
  schema.addDouble("mapping.depth_edge_threshold_m", &s.depth_edge_threshold_m, 0.0, 100.0);
  schema.addInt("mapping.stride", &s.stride, 1, 64);
}

}  // namespace dynamap
