#include <gtest/gtest.h>

#include <cstdlib>

#include "mapping_test_utils.hpp"

namespace dynamap::test {
namespace {

TEST(BackendRegistry, FindsTheFourBuiltInPlugins) {
  const auto names = BackendRegistry::scan({pluginDir()}).names();
  for (const char* n : {"points", "pcl_voxel", "vdb_tsdf", "octomap"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  }
}

// What a backend says of itself reaches the worker through the registry's wrapper (a capability
// the wrapper does not forward reads as the default).
TEST(BackendRegistry, CreatedBackendsSayWhatTheyNeedAndFuse) {
  const auto registry = BackendRegistry::scan({pluginDir()});
  EXPECT_FALSE(registry.create("vdb_tsdf", {})->needsPoints());  // projects voxels into depth
  EXPECT_TRUE(registry.create("vdb_tsdf", {})->fusesViews());
  EXPECT_TRUE(registry.create("points", {})->needsPoints());
  EXPECT_FALSE(registry.create("points", {})->fusesViews());
  EXPECT_TRUE(registry.create("octomap", {})->needsPoints());  // inserts point rays
}

TEST(BackendRegistry, UnknownNameListsThePluginsFound) {
  const auto registry = BackendRegistry::scan({pluginDir()});
  try {
    registry.create("no_such_backend", {});
    FAIL() << "no exception";
  } catch (const MappingError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("no_such_backend"), std::string::npos) << msg;
    for (const auto& n : registry.names()) EXPECT_NE(msg.find(n), std::string::npos) << msg;
  }
}

TEST(BackendRegistry, BadValueNamesTheKey) {
  const auto registry = BackendRegistry::scan({pluginDir()});
  const std::map<std::string, std::pair<std::string, std::string>> bad = {
      {"points", {"keep_every", "0"}},
      {"pcl_voxel", {"voxel_size_m", "abc"}},
      {"vdb_tsdf", {"space_carving", "maybe"}},
      {"octomap", {"up_axis", "w"}},
  };
  for (const auto& [backend, kv] : bad) {
    if (registry.pluginPath(backend).empty()) continue;
    try {
      registry.create(backend, {{kv.first, kv.second}});
      ADD_FAILURE() << backend << ": no exception";
    } catch (const MappingError& e) {
      EXPECT_NE(std::string(e.what()).find("mapping.params." + backend + "." + kv.first),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(BackendRegistry, ParamsForBackendStripsThePrefix) {
  const std::map<std::string, std::string> all = {
      {"vdb_tsdf.voxel_size_m", "0.01"}, {"octomap.resolution_m", "0.1"}, {"vdb_tsdfx.a", "1"}};
  const BackendParams p = paramsForBackend(all, "vdb_tsdf");
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p.at("voxel_size_m"), "0.01");
}

TEST(BackendRegistry, LoadsTheOutOfTreeExamplePlugin) {
  EXPECT_TRUE(BackendRegistry::scan({pluginDir()}).pluginPath("example").empty());
  ::setenv("DYNAMAP_PLUGIN_PATH", "/nonexistent:" DYNAMAP_EXAMPLE_PLUGIN_DIR, 1);
  const auto registry = BackendRegistry::scan({pluginDir()});
  ::unsetenv("DYNAMAP_PLUGIN_PATH");
  ASSERT_FALSE(registry.pluginPath("example").empty());
  auto backend = registry.create("example", {{"scale", "2"}});
  const SyntheticFrame f = SyntheticScene().render(0, 1);
  const PinholeCamera cam = SyntheticScene::camera();
  const std::vector<Eigen::Vector3f> pts = {Eigen::Vector3f(0, 0, 1), Eigen::Vector3f(1, 0, 2)};
  const std::vector<std::array<std::uint8_t, 3>> colors(2);
  KeyframeView view;
  view.T_W_C = f.T_W_C;
  view.camera = &cam;
  view.bgr = &f.bgr;
  view.static_depth_m = &f.depth_m;
  view.points_C = &pts;
  view.colors = &colors;
  backend->integrate(view);
  EXPECT_EQ(backend->stats().keyframes, 1u);
  EXPECT_EQ(backend->stats().elements, 2u);
  EXPECT_THROW(registry.create("example", {{"bogus", "1"}}), MappingError);
}

}  // namespace
}  // namespace dynamap::test
