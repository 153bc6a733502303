// libFuzzer target: the saved map's reader (readMapStore, `--load-map`). The first byte picks
// the input: even = the bytes of a map.sqlite file; odd = SQL run on a small valid map
// (writeMapStore) before it is read, so the field checks see rows of any shape. Only
// MapFileError may come out, and a map that is read must be usable: dense ids, 32-byte
// descriptors, observations of existing landmarks, finite values.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include <sqlite3.h>

#include "dynamap/system/map_store.hpp"
#include "fuzz_util.hpp"

namespace {

dynamap::MapContents smallMap() {
  dynamap::MapContents map;
  for (int i = 0; i < 3; ++i) {
    dynamap::Landmark lm;
    lm.p_W = Eigen::Vector3d(0.1 * i, 0.2, 1.0 + i);
    lm.descriptor = cv::Mat(1, 32, CV_8U, cv::Scalar(17 * i));
    lm.keyframes = 1;
    map.landmarks.push_back(lm);
  }
  for (std::uint64_t k = 0; k < 2; ++k) {
    dynamap::MapKeyframe kf;
    kf.id = k;
    kf.timestamp_s = 10.0 + k;
    kf.T_W_C.translation() = Eigen::Vector3d(0.05 * k, 0.0, 0.0);
    kf.observations.push_back({k, Eigen::Vector2d(100.0, 200.0), 1.5});
    kf.observations.push_back({2, Eigen::Vector2d(300.0, 50.0), 0.0});
    map.keyframes.push_back(kf);
  }
  return map;
}

void runSql(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) == SQLITE_OK) {
    sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr);  // errors: the map stays as is
  }
  sqlite3_close(db);
}

void checkUsable(const dynamap::MapContents& map) {
  for (std::size_t i = 0; i < map.landmarks.size(); ++i) {
    const auto& lm = map.landmarks[i];
    if (lm.descriptor.rows != 1 || lm.descriptor.cols != 32 || lm.descriptor.type() != CV_8U) {
      dynamap::fuzz::fail("descriptor is not 1 x 32 bytes");
    }
    if (!lm.p_W.allFinite()) dynamap::fuzz::fail("landmark not finite");
  }
  for (std::size_t k = 0; k < map.keyframes.size(); ++k) {
    const auto& kf = map.keyframes[k];
    if (kf.id != k) dynamap::fuzz::fail("keyframe ids not dense");
    if (!kf.T_W_C.matrix().allFinite()) dynamap::fuzz::fail("keyframe pose not finite");
    for (const auto& o : kf.observations) {
      if (o.landmark_id >= map.landmarks.size()) dynamap::fuzz::fail("observation of no landmark");
      if (!o.px.allFinite() || !std::isfinite(o.depth_m)) dynamap::fuzz::fail("observation");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string rest(reinterpret_cast<const char*>(data) + 1, size - 1);
  const dynamap::PinholeCamera camera;
  std::string path;
  if (data[0] % 2 == 0) {
    path = dynamap::fuzz::writeScratch("map.sqlite", rest);
  } else {
    path = dynamap::fuzz::scratchDir() + "/edited.sqlite";
    try {
      dynamap::writeMapStore(path, smallMap(), camera, "pcl_voxel");
    } catch (const dynamap::MapFileError& e) {
      dynamap::fuzz::fail(std::string("writing the small map failed: ") + e.what());
    }
    runSql(path, rest);
  }
  try {
    checkUsable(dynamap::readMapStore(path, camera));
  } catch (const dynamap::MapFileError&) {
  }
  return 0;
}
