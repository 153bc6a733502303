#include "dynamap/mapping/backend_registry.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace dynamap {
namespace {

constexpr const char* kPrefix = "libdynamap_backend_";
constexpr const char* kSuffix = ".so";

// Forwards to the plugin's backend and keeps the library loaded until the backend is gone
// (members are destroyed in reverse order: inner_ before handle_).
class PluginBackend final : public MapBackend {
 public:
  PluginBackend(std::shared_ptr<void> handle, std::unique_ptr<MapBackend> inner)
      : handle_(std::move(handle)), inner_(std::move(inner)) {}
  void integrate(const KeyframeView& view) override { inner_->integrate(view); }
  void updatePose(std::uint64_t id, const Eigen::Isometry3d& T_W_C) override {
    inner_->updatePose(id, T_W_C);
  }
  PoseUpdateMode poseUpdateMode() const override { return inner_->poseUpdateMode(); }
  void reset() override { inner_->reset(); }
  void exportMap(const std::string& dir) override { inner_->exportMap(dir); }
  MapStats stats() const override { return inner_->stats(); }
  bool fusesViews() const override { return inner_->fusesViews(); }
  bool needsPoints() const override { return inner_->needsPoints(); }
  bool importMap(const std::string& dir) override { return inner_->importMap(dir); }
  bool canDeintegrate() const override { return inner_->canDeintegrate(); }
  double cellSizeM() const override { return inner_->cellSizeM(); }
  void deintegrate(const KeyframeView& view) override { inner_->deintegrate(view); }
  void moveKeyframe(const KeyframeView& from, const KeyframeView& to) override {
    inner_->moveKeyframe(from, to);
  }

 private:
  std::shared_ptr<void> handle_;
  std::unique_ptr<MapBackend> inner_;
};

std::vector<std::string> splitPath(const char* text) {
  std::vector<std::string> out;
  if (text == nullptr) return out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ':')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

}  // namespace

BackendRegistry BackendRegistry::scan(const std::vector<std::string>& plugin_dirs) {
  namespace fs = std::filesystem;
  std::vector<std::string> dirs = plugin_dirs;
  for (auto& d : splitPath(std::getenv("DYNAMAP_PLUGIN_PATH"))) dirs.push_back(d);
  BackendRegistry registry;
  const std::string prefix = kPrefix;
  const std::string suffix = kSuffix;
  for (const auto& dir : dirs) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) continue;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      const std::string file = entry.path().filename().string();
      if (file.size() <= prefix.size() + suffix.size() || file.rfind(prefix, 0) != 0 ||
          file.compare(file.size() - suffix.size(), suffix.size(), suffix) != 0) {
        continue;
      }
      const std::string name =
          file.substr(prefix.size(), file.size() - prefix.size() - suffix.size());
      registry.plugins_.emplace(name, entry.path().string());  // first folder wins
    }
  }
  return registry;
}

std::vector<std::string> BackendRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& kv : plugins_) out.push_back(kv.first);
  return out;
}

std::string BackendRegistry::pluginPath(const std::string& name) const {
  const auto it = plugins_.find(name);
  return it == plugins_.end() ? std::string() : it->second;
}

std::unique_ptr<MapBackend> BackendRegistry::create(const std::string& name,
                                                    const BackendParams& params) const {
  const auto it = plugins_.find(name);
  if (it == plugins_.end()) {
    std::string list;
    for (const auto& n : names()) list += (list.empty() ? "" : ", ") + n;
    throw MappingError("mapping.backend: unknown backend '" + name +
                       "' (plugins found: " + (list.empty() ? std::string("none") : list) +
                       "; add folders with DYNAMAP_PLUGIN_PATH)");
  }
  // RTLD_NODELETE: a plugin and its dependencies stay mapped until exit. Their static data must
  // outlive dlclose (OctoMap registers tree prototypes in static initialisers; LeakSanitizer
  // reported them as leaked once the plugin was unloaded).
  void* raw = dlopen(it->second.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (raw == nullptr) {
    throw MappingError("backend plugin " + it->second + ": dlopen failed: " + dlerror());
  }
  std::shared_ptr<void> handle(raw, [](void* h) { dlclose(h); });
  void* symbol = dlsym(raw, kBackendFactorySymbol);
  if (symbol == nullptr) {
    throw MappingError("backend plugin " + it->second + ": no symbol " + kBackendFactorySymbol);
  }
  auto factory = reinterpret_cast<BackendFactoryFn>(symbol);
  std::unique_ptr<MapBackend> inner(factory(params));
  if (!inner) throw MappingError("backend plugin " + it->second + ": factory returned null");
  return std::make_unique<PluginBackend>(std::move(handle), std::move(inner));
}

BackendParams paramsForBackend(const std::map<std::string, std::string>& all_params,
                               const std::string& backend) {
  BackendParams out;
  const std::string prefix = backend + ".";
  for (const auto& kv : all_params) {
    if (kv.first.rfind(prefix, 0) == 0) out[kv.first.substr(prefix.size())] = kv.second;
  }
  return out;
}

}  // namespace dynamap
