#include "plugin_paths.hpp"

#include <dlfcn.h>

#include <filesystem>

namespace dynamap {

std::vector<std::string> defaultPluginDirs() {
  namespace fs = std::filesystem;
  std::vector<std::string> dirs;
  const auto add_lib_dir = [&dirs](const fs::path& lib_dir) {
    dirs.push_back((lib_dir / "dynamap").string());
    dirs.push_back(lib_dir.string());
  };
  std::error_code ec;
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&defaultPluginDirs), &info) != 0 &&
      info.dli_fname != nullptr) {
    const fs::path library = fs::canonical(info.dli_fname, ec);
    if (!ec) add_lib_dir(library.parent_path());
  }
  // A static build: the program's ../lib (as <prefix>/bin/dynamap -> <prefix>/lib).
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) add_lib_dir(exe.parent_path().parent_path() / "lib");
  dirs.push_back(DYNAMAP_PLUGIN_BUILD_DIR);
  return dirs;
}

}  // namespace dynamap
