// Regression tests for inputs found by the fuzz targets (fuzz/). Each test holds the crashing
// input inline (reduced by hand) and checks the reader now fails cleanly or reads it right.
// Under scripts/sanitize.sh asan the old code fails these with ASan/UBSan reports.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "dynamap/mapping/map_backend.hpp"  // MappingError
#include "dynamap/mapping/ply_io.hpp"
#include "dynamap/system/app_config.hpp"
#include "map_metrics.hpp"
#include "ply_colored.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

namespace fs = std::filesystem;

std::string writeFile(const std::string& name, const std::string& bytes) {
  const fs::path dir = test::freshTempDir("fuzz_regression_" + name);
  const fs::path path = dir / name;
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path.string();
}

template <typename T>
std::string bytesOf(T v) {
  std::string s(sizeof(T), '\0');
  std::memcpy(s.data(), &v, sizeof(T));
  return s;
}

std::string floatVertex(float x, float y, float z) { return bytesOf(x) + bytesOf(y) + bytesOf(z); }

const std::string kBinaryHeader = "ply\nformat binary_little_endian 1.0\n";

// ply_fuzzer crash 83b0c5cc: a face index of -2140970000 (int) was cast to uint32 (UBSan:
// "outside the range of representable values of type 'unsigned int'").
TEST(FuzzRegression, PlyNegativeFaceIndexIsAnError) {
  std::string ply = kBinaryHeader +
                    "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  ply += floatVertex(0, 0, 0) + floatVertex(1, 0, 0) + floatVertex(0, 1, 0);
  ply += std::string(1, '\3') + bytesOf<std::int32_t>(0) + bytesOf<std::int32_t>(-2140970000) +
         bytesOf<std::int32_t>(2);
  const std::string path = writeFile("neg_face.ply", ply);
  EXPECT_THROW(readPly(path, /*with_faces=*/true), MappingError);
  EXPECT_EQ(readPly(path, /*with_faces=*/false).vertices.size(), 3u);
  EXPECT_THROW(readPlyForPreview(path, 0), std::runtime_error);
}

// Faces that index past the vertices made preview/mesh code read out of bounds later.
TEST(FuzzRegression, PlyFaceIndexPastTheVerticesIsAnError) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n";
  EXPECT_THROW(readPly(writeFile("far_face.ply", ply), true), MappingError);
}

// A header announcing 10^12 vertices in a tiny file: reserve()/block allocation of terabytes
// (ASan allocation-size-too-big; std::length_error / bad_alloc without ASan).
TEST(FuzzRegression, PlyHugeVertexCountIsAnError) {
  for (const std::string& format : {std::string("binary_little_endian"), std::string("ascii")}) {
    const std::string ply = "ply\nformat " + format +
                            " 1.0\nelement vertex 1000000000000\nproperty float x\n"
                            "property float y\nproperty float z\nend_header\n" +
                            floatVertex(1, 2, 3);
    const std::string path = writeFile("huge_" + format + ".ply", ply);
    EXPECT_THROW(readPly(path), MappingError) << format;
    EXPECT_THROW(readPlyVertices(path), std::runtime_error) << format;
    EXPECT_THROW(readPlyForPreview(path, 1000), std::runtime_error) << format;
    EXPECT_THROW(readPlyForPreview(path, 0), std::runtime_error) << format;
  }
}

// A negative list length ("-1" read as a count) resized a vector to 2^64 - 1 elements.
TEST(FuzzRegression, PlyNegativeListLengthIsAnError) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n"
      "0 0 0\n-1 0 0 0\n";
  EXPECT_THROW(readPly(writeFile("neg_list.ply", ply), true), MappingError);
}

// Colours stored as float outside [0, 255] (or NaN) were cast to uint8 (UB): now clamped.
TEST(FuzzRegression, PlyFloatColoursAreClamped) {
  std::string ply = kBinaryHeader +
                    "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                    "property float red\nproperty float green\nproperty float blue\nend_header\n";
  ply += floatVertex(1, 2, 3) + bytesOf(300.0f) + bytesOf(-5.0f) +
         bytesOf(std::numeric_limits<float>::quiet_NaN());
  const PlyData data = readPly(writeFile("float_colours.ply", ply));
  ASSERT_EQ(data.colors.size(), 1u);
  EXPECT_EQ(data.colors[0][0], 255);
  EXPECT_EQ(data.colors[0][1], 0);
  EXPECT_EQ(data.colors[0][2], 0);
}

// readPlyForPreview's fast path read every coordinate as the type of the last one: float x, y
// with double z read 8 bytes at float offsets, past the end of the last record (ASan
// heap-buffer-overflow) and wrong values. Mixed layouts now use the general reader.
TEST(FuzzRegression, PlyPreviewWithMixedCoordinateTypes) {
  std::string ply = kBinaryHeader +
                    "element vertex 2\nproperty double z\nproperty float x\nproperty float y\n"
                    "end_header\n";
  ply += bytesOf(3.0) + bytesOf(1.0f) + bytesOf(2.0f);
  ply += bytesOf(6.0) + bytesOf(4.0f) + bytesOf(5.0f);
  std::size_t total = 0;
  const PlyData data = readPlyForPreview(writeFile("mixed.ply", ply), 0, &total);
  EXPECT_EQ(total, 2u);
  ASSERT_EQ(data.vertices.size(), 2u);
  EXPECT_FLOAT_EQ(data.vertices[1].x(), 4.0f);
  EXPECT_FLOAT_EQ(data.vertices[1].y(), 5.0f);
  EXPECT_FLOAT_EQ(data.vertices[1].z(), 6.0f);
}

// An element without properties and a count of 10^18 looped 10^18 times doing nothing.
TEST(FuzzRegression, PlyElementWithoutPropertiesIsSkipped) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement camera 1000000000000000000\n"
      "element vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n1 2 3\n";
  const PlyData data = readPly(writeFile("empty_element.ply", ply));
  ASSERT_EQ(data.vertices.size(), 1u);
  EXPECT_FLOAT_EQ(data.vertices[0].z(), 3.0f);
}

// ply_fuzzer crash 58171a06: two vertex elements, one with colours and one without, gave
// 4 colours for 8 vertices (readers index colours by vertex).
TEST(FuzzRegression, PlyTwoVertexElementsAreAnError) {
  std::string ply = kBinaryHeader +
                    "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                    "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  ply += floatVertex(1, 2, 3) + floatVertex(4, 5, 6) + "abc";
  EXPECT_THROW(readPly(writeFile("two_vertex.ply", ply)), MappingError);
}

// A map point at 1e30 m overflowed the int64 voxel key (UBSan float-cast-overflow).
TEST(FuzzRegression, VoxelCentroidsOfFarPoints) {
  const std::vector<Eigen::Vector3f> points = {
      {1e30f, -1e30f, 3e38f}, {0.01f, 0.01f, 0.01f}, {0.02f, 0.02f, 0.02f}};
  const auto centroids = voxelCentroids(points, 0.05);
  EXPECT_EQ(centroids.size(), 2u);
}

// config_fuzzer crash 15f29bd9: a YAML key that is itself a map or a list escaped as
// YAML::TypedBadConversion (std::terminate in `dynamap run`) instead of a ConfigError.
TEST(FuzzRegression, ConfigKeyThatIsNotAScalarIsAConfigError) {
  for (const std::string yaml :
       {"camera:\n  ? [a, b]\n  : freiburg2\n", "camera:\n  ? {p: q}\n  : 1\n", "? [x]\n: 1\n"}) {
    ConfigSchema schema;
    AppConfig config;
    bindAppConfig(schema, config);
    try {
      schema.loadYamlString(yaml, "fuzzed.yaml");
      ADD_FAILURE() << "accepted: " << yaml;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("fuzzed.yaml:"), std::string::npos) << e.what();
    }
  }
}

// config_fuzzer crash a7ae88c7: the effective config (written as config.yaml by every run)
// did not load again: yaml-cpp wrote the value "b:\r" unquoted ("illegal map value").
TEST(FuzzRegression, EffectiveConfigLoadsAgain) {
  const std::vector<std::string> overrides = {
      "mapping.params.points.a=b:\r",
      "mapping.params.octomap.k\xc3\xa7=v:", "dynamic.high_dynamic_classes=person:,car\r",
      "dynamic.model_cfg=/x\x01y"};
  std::string effective;
  const AppConfig config = loadAppConfig("", overrides, &effective);
  ConfigSchema schema;
  AppConfig again;
  bindAppConfig(schema, again);
  ASSERT_NO_THROW(schema.loadYamlString(effective, "effective")) << effective;
  EXPECT_EQ(again.mapping.params, config.mapping.params);
  EXPECT_EQ(again.dynamic.high_dynamic_classes, config.dynamic.high_dynamic_classes);
  EXPECT_EQ(again.dynamic.model_cfg, config.dynamic.model_cfg);
  // config_fuzzer crash 6ee5f8be: a 300-byte key (1800 characters once escaped) was written
  // as an implicit key, which YAML limits to 1024 characters.
  const std::string long_key = "mapping.params.points." + std::string(300, '\xff') + "=1";
  loadAppConfig("", {long_key, "mapping.params.points." + std::string(2000, 'k') + "=2"},
                &effective);
  EXPECT_NO_THROW(schema.loadYamlString(effective, "effective")) << effective;
  // Bytes that are not UTF-8 come back as U+FFFD, but the file still loads.
  loadAppConfig("", {"mapping.params.points.k\x8c\x8f=b:\r"}, &effective);
  EXPECT_NO_THROW(schema.loadYamlString(effective, "effective")) << effective;
}

// config_fuzzer crash bf3d19ae: "mapping.params.points...." (hundreds of dots) nested unnamed
// maps ~500 deep in the effective config, which yaml-cpp then failed to read ("bad file").
// Such keys are now refused up front, naming the key.
TEST(FuzzRegression, PluginParameterKeyWithEmptyPartsIsAConfigError) {
  for (const std::string& bad : std::vector<std::string>{
           "mapping.params.points" + std::string(400, '.') + "x=1", "mapping.params.points..x=1",
           "mapping.params.points.x.=1", "mapping.params..x=1", "mapping.params.a.b.c.d.e=1"}) {
    try {
      loadAppConfig("", {bad}, nullptr);
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("mapping.params."), std::string::npos) << e.what();
    }
  }
  const std::string yaml_path = writeFile("deep.yaml",
                                          "mapping:\n  params:\n    points:\n      "
                                          "a:\n        b:\n          c:\n"
                                          "            d: 1\n");
  EXPECT_THROW(loadAppConfig(yaml_path, {}, nullptr), ConfigError);
  // Ordinary plugin parameters still work.
  const AppConfig ok = loadAppConfig("", {"mapping.params.points.voxel_m=0.01"}, nullptr);
  EXPECT_EQ(ok.mapping.params.at("points.voxel_m"), "0.01");
}

}  // namespace
}  // namespace dynamap
