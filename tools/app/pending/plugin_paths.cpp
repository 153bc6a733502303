#include "plugin_paths.hpp"

#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace dynamap {

std::vector<std::string> pluginSearchPath() {
  namespace fs = std::filesystem;
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("DYNAMAP_PLUGIN_PATH")) {
    std::stringstream ss(env);
    std::string dir;
    while (std::getline(ss, dir, ':')) {
      if (!dir.empty()) dirs.push_back(dir);
    }
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    dirs.push_back((exe.parent_path().parent_path() / "lib" / "dynamap").string());
    dirs.push_back((exe.parent_path().parent_path() / "lib").string());
  }
  dirs.push_back(DYNAMAP_PLUGIN_BUILD_DIR);
  return dirs;
}

}  // namespace dynamap
