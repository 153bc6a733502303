#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "dynamap/mapping/map_backend.hpp"

namespace dynamap {

/// Finds backend plugins (files named libdynamap_backend_<name>.so) in explicit folders plus the
/// colon-separated folders of the environment variable DYNAMAP_PLUGIN_PATH, and creates backends
/// by name. Plugins are dlopen()ed on create() and stay loaded until exit (RTLD_NODELETE), so
/// their libraries' static data outlives every backend. No static-initializer registration.
/// Thread-safe after scan().
class BackendRegistry {
 public:
  static BackendRegistry scan(const std::vector<std::string>& plugin_dirs);
  /// Sorted backend names found.
  std::vector<std::string> names() const;
  /// Path of the plugin file for `name` (empty if unknown).
  std::string pluginPath(const std::string& name) const;
  /// Throws MappingError listing the names found for an unknown name, naming the file for a
  /// plugin without the factory symbol, and the key for a bad parameter.
  std::unique_ptr<MapBackend> create(const std::string& name, const BackendParams& params) const;

 private:
  std::map<std::string, std::string> plugins_;  ///< name -> file (first folder wins)
};

/// Keeps from MappingConfig::params ("<backend>.<key>" -> value) the keys of `backend`, without
/// the prefix.
BackendParams paramsForBackend(const std::map<std::string, std::string>& all_params,
                               const std::string& backend);

}  // namespace dynamap
