#include <gtest/gtest.h>

#include "dynamap/mapping/backend_registry.hpp"
#include "dynamap/system/app_config.hpp"

namespace dynamap {
namespace {

TEST(MappingConfig, BindsStaticPointOptionsAndBackendParams) {
  const AppConfig cfg = loadAppConfig(
      "", {"mapping.backend=vdb_tsdf", "mapping.mask_dilation_px=3", "mapping.depth_max_m=3.5",
           "mapping.stride=2", "mapping.params.vdb_tsdf.voxel_size_m=0.01"});
  EXPECT_EQ(cfg.mapping.static_points.mask_dilation_px, 3);
  EXPECT_DOUBLE_EQ(cfg.mapping.static_points.depth_max_m, 3.5);
  EXPECT_EQ(cfg.mapping.static_points.stride, 2);
  const BackendParams p = paramsForBackend(cfg.mapping.params, cfg.mapping.backend);
  EXPECT_EQ(p.at("voxel_size_m"), "0.01");
}

TEST(MappingConfig, BadValueNamesTheKey) {
  try {
    loadAppConfig("", {"mapping.mask_dilation_px=-1"});
    FAIL() << "no exception";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("mapping.mask_dilation_px"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace dynamap
