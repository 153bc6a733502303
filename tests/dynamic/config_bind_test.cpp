#include <gtest/gtest.h>

#include "dynamap/core/dynamic/class_table.hpp"
#include "dynamap/system/app_config.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

TEST(DynamicConfigBinding, EveryFieldIsAKeyAndTheClassTableIsOverridable) {
  DynamicConfig c;
  ConfigSchema schema;
  bindDynamicConfig(schema, c);
  const auto keys = schema.keys();
  for (const char* k :
       {"dynamic.mode", "dynamic.epipolar_threshold_px", "dynamic.detector", "dynamic.model_cfg",
        "dynamic.model_weights", "dynamic.nms", "dynamic.high_dynamic_classes",
        "dynamic.moving_ratio", "dynamic.reprojection_threshold_px", "dynamic.depth_band_m"}) {
    EXPECT_NE(std::find(keys.begin(), keys.end(), k), keys.end()) << k;
  }
  schema.loadYamlString(
      "dynamic:\n  detector: nanodet_onnx\n  high_dynamic_classes: [person, dog]\n"
      "  class_weights:\n    chair: 0.05\n  nms: plain\n",
      "test");
  EXPECT_EQ(c.detector, "nanodet_onnx");
  EXPECT_EQ(c.nms, "plain");
  const ClassTable t(c);
  EXPECT_TRUE(t.isHighDynamic(ClassTable::classIndex("dog")));
  EXPECT_FALSE(t.isHighDynamic(ClassTable::classIndex("car")));
  EXPECT_DOUBLE_EQ(t.weight(ClassTable::classIndex("chair")), 0.05);
  EXPECT_THROW(schema.applyOverride("dynamic.detector=resnet"), ConfigError);
  EXPECT_THROW(schema.applyOverride("dynamic.nms=greedy"), ConfigError);
}

TEST(DynamicConfigBinding, RelativeModelPathsResolveAgainstTheConfigFilesParent) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  DynamicConfig c;  // defaults: ../shared/models/yolo-fastest/...
  resolveDynamicModelPaths(c, (test::sourceDir() / "config/default.yaml").string());
  EXPECT_TRUE(std::filesystem::path(c.model_cfg).is_absolute()) << c.model_cfg;
  EXPECT_TRUE(std::filesystem::exists(c.model_weights)) << c.model_weights;
  DynamicConfig missing;
  missing.model_weights = "models/none.weights";
  resolveDynamicModelPaths(missing, (test::sourceDir() / "config/default.yaml").string());
  EXPECT_EQ(missing.model_weights, "models/none.weights");  // left for the factory to report
}

}  // namespace
}  // namespace dynamap

namespace dynamap {
namespace {

TEST(DynamicConfigBinding, ExampleClassTableFileLoadsAndItsModelsExist) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const AppConfig c =
      loadAppConfig((test::sourceDir() / "config/detector_classes.yaml").string(), {});
  EXPECT_TRUE(std::filesystem::exists(c.dynamic.model_cfg)) << c.dynamic.model_cfg;
  EXPECT_TRUE(std::filesystem::exists(c.dynamic.model_weights)) << c.dynamic.model_weights;
  EXPECT_EQ(ClassTable(c.dynamic).weight(ClassTable::classIndex("chair")), 0.5);
}

TEST(DynamicConfigBinding, MoversConfigTurnsOnTheMoverKeys) {
  const AppConfig c = loadAppConfig((test::sourceDir() / "config/movers.yaml").string(), {});
  EXPECT_TRUE(c.dynamic.mover_tracks);
  EXPECT_EQ(c.dynamic.mover_view_frames, 12);
  EXPECT_TRUE(c.dynamic.mover_follow_anchors);
  EXPECT_TRUE(c.dynamic.hold_moved_objects);
  EXPECT_DOUBLE_EQ(c.dynamic.dense_barrier_step_m, 0.03);
  const AppConfig d = loadAppConfig((test::sourceDir() / "config/default.yaml").string(), {});
  EXPECT_TRUE(d.dynamic.mover_tracks);
  EXPECT_EQ(d.dynamic.mover_view_frames, 12);
  EXPECT_FALSE(d.dynamic.mover_follow_anchors);
  EXPECT_DOUBLE_EQ(d.dynamic.dense_barrier_step_m, 0.0);
  EXPECT_TRUE(d.dynamic.hold_moved_objects);
}

}  // namespace
}  // namespace dynamap
