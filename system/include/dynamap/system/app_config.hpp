#pragma once

#include <string>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/dynamic_config.hpp"
#include "dynamap/core/tracker_config.hpp"
#include "dynamap/mapping/mapping_config.hpp"
#include "dynamap/system/config_schema.hpp"

namespace dynamap {

struct CameraSettings {
  std::string preset = "freiburg3";  ///< freiburg1 | freiburg2 | freiburg3 | custom
  PinholeCamera custom;              ///< used when preset == custom
  double depth_scale = 5000.0;       ///< depth PNG units per metre
};

struct DatasetSettings {
  double max_time_diff_s = 0.02;  ///< colour/depth association window
  int max_frames = 0;             ///< 0 = all frames
  /// Colour frames with no depth frame within max_time_diff_s: true = posed without depth, no
  /// other pose changes (every colour frame gets a pose), false = skipped (as TUM's associate.py).
  bool keep_unassociated_rgb = true;
};

/// Everything a run is configured with. Defaults live in the section structs.
struct AppConfig {
  CameraSettings camera;
  DatasetSettings dataset;
  TrackerConfig tracking;
  DynamicConfig dynamic;
  MappingConfig mapping;

  /// The camera the run uses (preset or custom).
  PinholeCamera resolvedCamera() const;
};

void bindBaseConfig(ConfigSchema& schema, AppConfig& config);  // camera, dataset
void bindTrackingConfig(ConfigSchema& schema, TrackerConfig& config);
void bindDynamicConfig(ConfigSchema& schema, DynamicConfig& config);
void bindMappingConfig(ConfigSchema& schema, MappingConfig& config);

/// Binds every section of `config` to `schema`.
void bindAppConfig(ConfigSchema& schema, AppConfig& config);

/// Default config, then `config_path` (if not empty), then each "--set key=value".
/// Throws ConfigError naming the file/line/key.
AppConfig loadAppConfig(const std::string& config_path, const std::vector<std::string>& overrides,
                        std::string* effective_yaml = nullptr);

}  // namespace dynamap
