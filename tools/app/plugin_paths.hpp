#pragma once

#include <string>
#include <vector>

namespace dynamap {

/// Folders searched for mapping-backend plugins besides $DYNAMAP_PLUGIN_PATH (which
/// BackendRegistry adds itself): <exe>/../lib/dynamap, <exe>/../lib, the build tree's lib.
std::vector<std::string> pluginSearchPath();

}  // namespace dynamap
