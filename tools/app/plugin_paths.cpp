#include "plugin_paths.hpp"

#include <filesystem>

namespace dynamap {

std::vector<std::string> pluginSearchPath() {
  namespace fs = std::filesystem;
  std::vector<std::string> dirs;
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
