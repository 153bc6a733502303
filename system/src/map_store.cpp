#include "dynamap/system/map_store.hpp"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>

#include "sqlite_db.hpp"

namespace dynamap {
namespace {

template <typename T>
void append(std::string& bytes, T value) {
  const auto* p = reinterpret_cast<const char*>(&value);
  bytes.append(p, sizeof(T));
}

std::string packObservations(const std::vector<KeyframeObservation>& observations) {
  std::string bytes;
  bytes.reserve(observations.size() * kObservationBytes);
  for (const auto& o : observations) {
    append(bytes, o.landmark_id);
    append(bytes, o.px.x());
    append(bytes, o.px.y());
    append(bytes, o.depth_m);
  }
  return bytes;
}

void writeMeta(Db& db, const std::map<std::string, std::string>& meta) {
  auto stmt = db.prepare("INSERT INTO meta VALUES (?, ?)", "meta");
  for (const auto& [key, value] : meta) {
    sqlite3_reset(stmt.get());
    sqlite3_bind_text(stmt.get(), 1, key.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(stmt.get(), 2, value.c_str(), -1, SQLITE_TRANSIENT);
    db.step(stmt.get(), "meta." + key);
  }
}

void writeLandmarks(Db& db, const std::vector<Landmark>& landmarks) {
  auto stmt = db.prepare("INSERT INTO landmarks VALUES (?, ?, ?, ?, ?, ?, ?)", "landmarks");
  for (std::size_t i = 0; i < landmarks.size(); ++i) {
    const Landmark& lm = landmarks[i];
    sqlite3_stmt* s = stmt.get();
    sqlite3_reset(s);
    sqlite3_bind_int64(s, 1, static_cast<sqlite3_int64>(i));
    for (int k = 0; k < 3; ++k) sqlite3_bind_double(s, 2 + k, lm.p_W[k]);
    const cv::Mat d = lm.descriptor.isContinuous() ? lm.descriptor : lm.descriptor.clone();
    sqlite3_bind_blob(s, 5, d.data, static_cast<int>(d.total() * d.elemSize()), SQLITE_TRANSIENT);
    sqlite3_bind_int(s, 6, lm.bad ? 1 : 0);
    sqlite3_bind_int(s, 7, lm.keyframes);
    db.step(s, "landmarks");
  }
}

void writeKeyframes(Db& db, const std::vector<MapKeyframe>& keyframes) {
  auto stmt =
      db.prepare("INSERT INTO keyframes VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)", "keyframes");
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    const MapKeyframe& kf = keyframes[k];
    sqlite3_stmt* s = stmt.get();
    sqlite3_reset(s);
    sqlite3_bind_int64(s, 1, static_cast<sqlite3_int64>(k));
    sqlite3_bind_double(s, 2, kf.timestamp_s);
    const Eigen::Vector3d t = kf.T_W_C.translation();
    const Eigen::Quaterniond q(kf.T_W_C.linear());
    const double pose[7] = {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
    for (int i = 0; i < 7; ++i) sqlite3_bind_double(s, 3 + i, pose[i]);
    sqlite3_bind_double(s, 10, kf.masked_share);
    const std::string obs = packObservations(kf.observations);
    sqlite3_bind_blob(s, 11, obs.data(), static_cast<int>(obs.size()), SQLITE_TRANSIENT);
    db.step(s, "keyframes");
  }
}

std::map<std::string, std::string> metaOf(const MapContents& contents, const PinholeCamera& camera,
                                          const std::string& backend) {
  auto number = [](double v) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.17g", v);
    return std::string(buf);
  };
  return {{"format_version", std::to_string(kMapFormatVersion)},
          {"camera.fx", number(camera.fx)},
          {"camera.fy", number(camera.fy)},
          {"camera.cx", number(camera.cx)},
          {"camera.cy", number(camera.cy)},
          {"camera.width", std::to_string(camera.width)},
          {"camera.height", std::to_string(camera.height)},
          {"backend", backend},
          {"landmarks", std::to_string(contents.landmarks.size())},
          {"keyframes", std::to_string(contents.keyframes.size())}};
}

}  // namespace

void writeMapStore(const std::string& path, const MapContents& contents,
                   const PinholeCamera& camera, const std::string& backend) {
  const std::string tmp_path = path + ".tmp";
  std::error_code ec;
  std::filesystem::remove(tmp_path, ec);
  {
    Db db(tmp_path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
    db.exec("PRAGMA journal_mode=OFF; PRAGMA synchronous=OFF; BEGIN;");
    db.exec(
        "CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);"
        "CREATE TABLE landmarks (id INTEGER PRIMARY KEY, x REAL, y REAL, z REAL,"
        " descriptor BLOB, bad INTEGER, keyframes INTEGER);"
        "CREATE TABLE keyframes (id INTEGER PRIMARY KEY, timestamp_s REAL, tx REAL, ty REAL,"
        " tz REAL, qx REAL, qy REAL, qz REAL, qw REAL, masked_share REAL, observations BLOB);");
    writeMeta(db, metaOf(contents, camera, backend));
    writeLandmarks(db, contents.landmarks);
    writeKeyframes(db, contents.keyframes);
    db.exec("COMMIT;");
  }
  std::filesystem::rename(tmp_path, path, ec);
  if (ec) throw MapFileError(path + ": cannot rename " + tmp_path + ": " + ec.message());
}

}  // namespace dynamap
