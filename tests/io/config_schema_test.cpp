#include "dynamap/system/config_schema.hpp"

#include <gtest/gtest.h>

#include "dynamap/system/app_config.hpp"

namespace dynamap {
namespace {

TEST(ConfigSchema, DefaultsLiveInCodeAndYamlOverrides) {
  AppConfig cfg;
  ConfigSchema schema;
  bindAppConfig(schema, cfg);
  EXPECT_EQ(cfg.camera.preset, "freiburg3");
  schema.loadYamlString("camera:\n  preset: freiburg1\ntracking:\n  lk_levels: 4\n", "t.yaml");
  EXPECT_EQ(cfg.camera.preset, "freiburg1");
  EXPECT_EQ(cfg.tracking.lk_levels, 4);
}

TEST(ConfigSchema, UnknownKeyNamesFileLineAndKey) {
  AppConfig cfg;
  ConfigSchema schema;
  bindAppConfig(schema, cfg);
  try {
    schema.loadYamlString("camera:\n  preset: freiburg3\n  fxx: 3\n", "bad.yaml");
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("camera.fxx"), std::string::npos) << e.what();
  }
}

TEST(ConfigSchema, OutOfRangeAndBadTypeAreErrors) {
  AppConfig cfg;
  ConfigSchema schema;
  bindAppConfig(schema, cfg);
  EXPECT_THROW(schema.applyOverride("tracking.lk_levels=0"), ConfigError);
  EXPECT_THROW(schema.applyOverride("tracking.lk_levels=abc"), ConfigError);
  EXPECT_THROW(schema.applyOverride("camera.preset=freiburg9"), ConfigError);
  EXPECT_THROW(schema.applyOverride("no_equals_sign"), ConfigError);
  EXPECT_THROW(schema.loadYamlString("camera: [1, 2\n", "broken.yaml"), ConfigError);
}

TEST(ConfigSchema, SetOverridesAndFreeFormPluginParams) {
  AppConfig cfg;
  ConfigSchema schema;
  bindAppConfig(schema, cfg);
  schema.applyOverride("camera.preset=freiburg2");
  schema.applyOverride("mapping.params.vdb_tsdf.voxel_size_m=0.01");
  EXPECT_EQ(cfg.camera.preset, "freiburg2");
  EXPECT_EQ(cfg.mapping.params.at("vdb_tsdf.voxel_size_m"), "0.01");
  const std::string dumped = schema.dumpYaml();
  EXPECT_NE(dumped.find("freiburg2"), std::string::npos);
  // The dump loads back into an identical configuration.
  AppConfig again;
  ConfigSchema schema2;
  bindAppConfig(schema2, again);
  schema2.loadYamlString(dumped, "dump");
  EXPECT_EQ(again.camera.preset, "freiburg2");
  EXPECT_EQ(again.mapping.params.at("vdb_tsdf.voxel_size_m"), "0.01");
}

}  // namespace
}  // namespace dynamap
