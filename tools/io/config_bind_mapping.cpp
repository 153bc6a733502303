#include "app_config.hpp"

namespace dynamap {

void bindMappingConfig(ConfigSchema& schema, MappingConfig& c) {
  schema.addString("mapping.backend", &c.backend);
  schema.addStringMap("mapping.params", &c.params);
}

}  // namespace dynamap
