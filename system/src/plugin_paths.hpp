#pragma once

#include <string>
#include <vector>

namespace dynamap {

/// Where backend plugins are looked for (after DYNAMAP_PLUGIN_PATH, which BackendRegistry
/// reads itself): <libdir>/dynamap and <libdir> of the library holding this code (an installed
/// tree), the program's ../lib, then the build tree's lib/ folder.
std::vector<std::string> defaultPluginDirs();

}  // namespace dynamap
