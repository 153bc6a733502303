#include "dynamap/core/dynamic_config.hpp"

#include <filesystem>

namespace dynamap {

namespace {

std::string resolveOne(const std::string& path, const std::filesystem::path& config_file) {
  namespace fs = std::filesystem;
  if (path.empty() || fs::path(path).is_absolute()) return path;
  std::error_code ec;
  if (fs::exists(path, ec)) return fs::absolute(path, ec).lexically_normal().string();
  if (!config_file.empty()) {
    const fs::path candidate = fs::absolute(config_file, ec).parent_path().parent_path() / path;
    if (fs::exists(candidate, ec)) return candidate.lexically_normal().string();
  }
  return path;
}

}  // namespace

void resolveDynamicModelPaths(DynamicConfig& config, const std::string& config_file) {
  config.model_cfg = resolveOne(config.model_cfg, config_file);
  config.model_weights = resolveOne(config.model_weights, config_file);
}

}  // namespace dynamap
