#pragma once

#include <string>
#include <vector>

namespace dynamap {

/// Folders searched for mapping-backend plugins, in order: $DYNAMAP_PLUGIN_PATH
/// (colon-separated), <exe>/../lib/dynamap, <exe>/../lib, then the build tree's lib folder.
std::vector<std::string> pluginSearchPath();

}  // namespace dynamap
