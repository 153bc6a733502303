// The saved map's store (map.sqlite): every field back as written, and every kind of bad file
// (truncated, another format version, another camera, rows that do not fit) refused with one
// MapFileError naming the file and the field.
#include "dynamap/system/map_store.hpp"

#include <filesystem>
#include <functional>
#include <string>

#include <gtest/gtest.h>
#include <sqlite3.h>

#include "test_paths.hpp"

namespace dynamap {
namespace {

MapContents sampleMap() {
  MapContents map;
  cv::RNG rng(3);
  for (int i = 0; i < 50; ++i) {
    Landmark lm;
    lm.p_W = Eigen::Vector3d(rng.uniform(-2.0, 2.0), rng.uniform(-1.0, 1.0), rng.uniform(1.0, 4.0));
    lm.descriptor = cv::Mat(1, 32, CV_8U);
    rng.fill(lm.descriptor, cv::RNG::UNIFORM, 0, 256);
    lm.bad = i % 7 == 0;
    lm.keyframes = 1 + i % 3;
    map.landmarks.push_back(lm);
  }
  for (std::uint64_t k = 0; k < 4; ++k) {
    MapKeyframe kf;
    kf.id = k;
    kf.timestamp_s = 1305031102.175304 + 0.5 * k;
    kf.T_W_C = Eigen::Translation3d(0.1 * k, -0.02 * k, 0.3) *
               Eigen::AngleAxisd(0.2 * k + 0.1, Eigen::Vector3d(1, 2, 3).normalized());
    kf.masked_share = 0.05 * k;
    for (std::uint64_t i = k; i < 50; i += 3) {
      kf.observations.push_back({i, Eigen::Vector2d(10.5 + i, 400.25 - i), i % 2 ? 0.0 : 1.25});
    }
    map.keyframes.push_back(kf);
  }
  return map;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const MapFileError& e) {
    return e.what();
  }
  return "";
}

void runSql(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sql;
  sqlite3_close(db);
}

std::string writeSample(const std::string& test_name) {
  const auto path = (test::freshTempDir(test_name) / kMapStoreFile).string();
  writeMapStore(path, sampleMap(), PinholeCamera{}, "pcl_voxel");
  return path;
}

TEST(MapStore, RoundTripKeepsEveryField) {
  const std::string path = writeSample("map_store_round_trip");
  MapStoreInfo info;
  const MapContents read = readMapStore(path, PinholeCamera{}, &info);
  const MapContents want = sampleMap();
  EXPECT_EQ(info.backend, "pcl_voxel");
  ASSERT_EQ(read.landmarks.size(), want.landmarks.size());
  for (std::size_t i = 0; i < want.landmarks.size(); ++i) {
    EXPECT_EQ(read.landmarks[i].p_W, want.landmarks[i].p_W) << i;  // doubles stored exactly
    EXPECT_EQ(
        cv::norm(read.landmarks[i].descriptor, want.landmarks[i].descriptor, cv::NORM_HAMMING), 0);
    EXPECT_EQ(read.landmarks[i].bad, want.landmarks[i].bad);
    EXPECT_EQ(read.landmarks[i].keyframes, want.landmarks[i].keyframes);
  }
  ASSERT_EQ(read.keyframes.size(), want.keyframes.size());
  for (std::size_t k = 0; k < want.keyframes.size(); ++k) {
    const MapKeyframe& a = read.keyframes[k];
    const MapKeyframe& b = want.keyframes[k];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.timestamp_s, b.timestamp_s);
    EXPECT_TRUE(a.T_W_C.isApprox(b.T_W_C, 1e-12)) << k;  // via a quaternion: rounding only
    EXPECT_EQ(a.masked_share, b.masked_share);
    ASSERT_EQ(a.observations.size(), b.observations.size());
    for (std::size_t i = 0; i < b.observations.size(); ++i) {
      EXPECT_EQ(a.observations[i].landmark_id, b.observations[i].landmark_id);
      EXPECT_EQ(a.observations[i].px, b.observations[i].px);
      EXPECT_EQ(a.observations[i].depth_m, b.observations[i].depth_m);
    }
  }
}

TEST(MapStore, MissingOrTruncatedFileIsOneErrorNamingTheFile) {
  const std::string path = writeSample("map_store_truncated");
  const std::string missing = errorOf([&] { readMapStore(path + ".nope", PinholeCamera{}); });
  EXPECT_NE(missing.find(path + ".nope"), std::string::npos) << missing;
  const auto size = std::filesystem::file_size(path);
  for (const double keep : {0.0, 0.3, 0.6, 0.9}) {
    const std::string cut = path + ".cut";
    std::filesystem::copy_file(path, cut, std::filesystem::copy_options::overwrite_existing);
    std::filesystem::resize_file(cut, static_cast<std::uintmax_t>(keep * size));
    const std::string error = errorOf([&] { readMapStore(cut, PinholeCamera{}); });
    EXPECT_NE(error.find(cut + ":"), std::string::npos) << "kept " << keep << ": " << error;
  }
}

TEST(MapStore, MissingRowsAreNamedByTable) {
  const std::string path = writeSample("map_store_rows");
  runSql(path, "DELETE FROM keyframes WHERE id = 3");
  const std::string error = errorOf([&] { readMapStore(path, PinholeCamera{}); });
  EXPECT_NE(error.find(path + ": table keyframes: 3 rows, meta.keyframes says 4"),
            std::string::npos)
      << error;
}

TEST(MapStore, OtherFormatVersionIsRefusedByName) {
  const std::string path = writeSample("map_store_version");
  runSql(path, "UPDATE meta SET value = '2' WHERE key = 'format_version'");
  const std::string error = errorOf([&] { readMapStore(path, PinholeCamera{}); });
  EXPECT_NE(error.find(path + ": meta.format_version: version 2, this dynamap reads version 1"),
            std::string::npos)
      << error;
}

TEST(MapStore, OtherCameraIsRefusedByName) {
  const std::string path = writeSample("map_store_camera");
  PinholeCamera other;
  other.fx = 517.3;  // freiburg1
  const std::string error = errorOf([&] { readMapStore(path, other); });
  EXPECT_NE(error.find(path + ": meta.camera.fx: the map was made with 535.4"), std::string::npos)
      << error;
  other = PinholeCamera{};
  other.width = 320;
  EXPECT_NE(errorOf([&] { readMapStore(path, other); }).find("meta.camera.width"),
            std::string::npos);
}

TEST(MapStore, RowsThatDoNotFitAreNamedByRowAndField) {
  const std::string path = writeSample("map_store_fields");
  const std::string copy = path + ".edit";
  const auto edited = [&](const std::string& sql) {
    std::filesystem::copy_file(path, copy, std::filesystem::copy_options::overwrite_existing);
    runSql(copy, sql);
    return errorOf([&] { readMapStore(copy, PinholeCamera{}); });
  };
  EXPECT_NE(edited("UPDATE keyframes SET observations = x'00' WHERE id = 1")
                .find("keyframes row 1: field observations has 1 bytes"),
            std::string::npos);
  EXPECT_NE(edited("DELETE FROM landmarks WHERE id = 49; UPDATE meta SET value = '49' WHERE key = "
                   "'landmarks'")
                .find("landmark 49 does not exist"),
            std::string::npos);
  EXPECT_NE(edited("UPDATE landmarks SET descriptor = x'0102' WHERE id = 5")
                .find("landmarks row 5: field descriptor has 2 bytes"),
            std::string::npos);
  EXPECT_NE(
      edited("UPDATE keyframes SET qw = 7 WHERE id = 2").find("keyframes row 2: field qx/qy/qz/qw"),
      std::string::npos);
  EXPECT_NE(edited("DELETE FROM meta WHERE key = 'camera.cy'").find("meta.camera.cy: missing"),
            std::string::npos);
}

}  // namespace
}  // namespace dynamap
