#pragma once

#include <map>
#include <string>

namespace dynamap {

/// Dense-mapping parameters, bound to YAML keys "mapping.<name>"
/// (tools/io/config_bind_mapping.cpp). Backend parameters are free-form under
/// "mapping.params.<backend>.<key>" and validated by the backend itself.
struct MappingConfig {
  std::string backend = "pcl_voxel";
  std::map<std::string, std::string> params;  ///< "<backend>.<key>" -> value
};

}  // namespace dynamap
