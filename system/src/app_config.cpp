#include "dynamap/system/app_config.hpp"

namespace dynamap {

PinholeCamera AppConfig::resolvedCamera() const {
  return camera.preset == "custom" ? camera.custom : cameraPreset(camera.preset);
}

void bindBaseConfig(ConfigSchema& schema, AppConfig& config) {
  auto& cam = config.camera;
  schema.addString("camera.preset", &cam.preset, {"freiburg1", "freiburg2", "freiburg3", "custom"});
  schema.addDouble("camera.fx", &cam.custom.fx, 1.0, 1e5);
  schema.addDouble("camera.fy", &cam.custom.fy, 1.0, 1e5);
  schema.addDouble("camera.cx", &cam.custom.cx, 0.0, 1e5);
  schema.addDouble("camera.cy", &cam.custom.cy, 0.0, 1e5);
  schema.addInt("camera.width", &cam.custom.width, 1, 100000);
  schema.addInt("camera.height", &cam.custom.height, 1, 100000);
  const char* names[] = {"k1", "k2", "p1", "p2", "k3"};
  for (int i = 0; i < 5; ++i) {
    schema.addDouble(std::string("camera.") + names[i], &cam.custom.distortion[i], -100.0, 100.0);
  }
  schema.addDouble("camera.depth_scale", &cam.depth_scale, 1.0, 1e6);
  schema.addDouble("dataset.max_time_diff_s", &config.dataset.max_time_diff_s, 0.0, 1.0);
  schema.addInt("dataset.max_frames", &config.dataset.max_frames, 0, 100000000);
  schema.addBool("dataset.keep_unassociated_rgb", &config.dataset.keep_unassociated_rgb);
}

void bindAppConfig(ConfigSchema& schema, AppConfig& config) {
  bindBaseConfig(schema, config);
  bindTrackingConfig(schema, config.tracking);
  bindDynamicConfig(schema, config.dynamic);
  bindMappingConfig(schema, config.mapping);
}

AppConfig loadAppConfig(const std::string& config_path, const std::vector<std::string>& overrides,
                        std::string* effective_yaml) {
  AppConfig config;
  ConfigSchema schema;
  bindAppConfig(schema, config);
  if (!config_path.empty()) schema.loadYamlFile(config_path);
  for (const auto& o : overrides) schema.applyOverride(o);
  // Relative detector model paths: CWD first, then the config file's directory's parent.
  resolveDynamicModelPaths(config.dynamic, config_path);
  if (effective_yaml != nullptr) *effective_yaml = schema.dumpYaml();
  return config;
}

}  // namespace dynamap
