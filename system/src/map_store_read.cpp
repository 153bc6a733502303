// readMapStore(): a saved map's tracker part, every field checked before it is used.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>

#include "dynamap/system/map_store.hpp"
#include "sqlite_db.hpp"

namespace dynamap {
namespace {

/// Errors name the file, the table or key, and the row.
class Reader {
 public:
  explicit Reader(const std::string& path) : db_(path, SQLITE_OPEN_READONLY) {}

  [[noreturn]] void bad(const std::string& field, const std::string& what) const {
    throw MapFileError(db_.path() + ": " + field + ": " + what);
  }

  std::map<std::string, std::string> meta() {
    std::map<std::string, std::string> out;
    auto stmt = db_.prepare("SELECT key, value FROM meta", "table meta");
    while (db_.step(stmt.get(), "table meta")) {
      const auto* key = sqlite3_column_text(stmt.get(), 0);
      const auto* value = sqlite3_column_text(stmt.get(), 1);
      if (key == nullptr || value == nullptr) bad("meta", "a key or value is missing");
      out[reinterpret_cast<const char*>(key)] = reinterpret_cast<const char*>(value);
    }
    return out;
  }

  std::vector<Landmark> landmarks() {
    std::vector<Landmark> out;
    auto stmt = db_.prepare(
        "SELECT id, x, y, z, descriptor, bad, keyframes FROM landmarks "
        "ORDER BY id",
        "table landmarks");
    sqlite3_stmt* s = stmt.get();
    while (db_.step(s, "table landmarks")) {
      const std::string row = "landmarks row " + std::to_string(out.size());
      expectDenseId(s, out.size(), row);
      Landmark lm;
      for (int k = 0; k < 3; ++k) lm.p_W[k] = sqlite3_column_double(s, 1 + k);
      if (!lm.p_W.allFinite()) bad(row, "field x/y/z is not finite");
      if (sqlite3_column_bytes(s, 4) != kDescriptorBytes) {
        bad(row, "field descriptor has " + std::to_string(sqlite3_column_bytes(s, 4)) +
                     " bytes, not 32");
      }
      lm.descriptor = cv::Mat(1, kDescriptorBytes, CV_8U);
      std::memcpy(lm.descriptor.data, sqlite3_column_blob(s, 4), kDescriptorBytes);
      lm.bad = sqlite3_column_int(s, 5) != 0;
      lm.keyframes = sqlite3_column_int(s, 6);
      out.push_back(std::move(lm));
    }
    return out;
  }

  std::vector<MapKeyframe> keyframes(std::size_t landmark_count) {
    std::vector<MapKeyframe> out;
    auto stmt = db_.prepare(
        "SELECT id, timestamp_s, tx, ty, tz, qx, qy, qz, qw, masked_share, "
        "observations FROM keyframes ORDER BY id",
        "table keyframes");
    sqlite3_stmt* s = stmt.get();
    while (db_.step(s, "table keyframes")) {
      const std::string row = "keyframes row " + std::to_string(out.size());
      MapKeyframe kf;
      kf.id = out.size();
      expectDenseId(s, kf.id, row);
      kf.timestamp_s = sqlite3_column_double(s, 1);
      const Eigen::Vector3d t(sqlite3_column_double(s, 2), sqlite3_column_double(s, 3),
                              sqlite3_column_double(s, 4));
      Eigen::Quaterniond q(sqlite3_column_double(s, 8), sqlite3_column_double(s, 5),
                           sqlite3_column_double(s, 6), sqlite3_column_double(s, 7));
      if (!std::isfinite(kf.timestamp_s)) bad(row, "field timestamp_s is not finite");
      if (!t.allFinite()) bad(row, "field tx/ty/tz is not finite");
      if (!q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-6) {
        bad(row, "field qx/qy/qz/qw is not a unit quaternion");
      }
      kf.T_W_C.linear() = q.normalized().toRotationMatrix();
      kf.T_W_C.translation() = t;
      kf.masked_share = sqlite3_column_double(s, 9);
      if (!(kf.masked_share >= 0.0 && kf.masked_share <= 1.0)) {
        bad(row, "field masked_share is not in [0, 1]");
      }
      kf.observations = observations(s, 10, landmark_count, row);
      out.push_back(std::move(kf));
    }
    return out;
  }

 private:
  /// Column 0 of the row must be `expected`: ids are dense, landmarks[i] has id i.
  void expectDenseId(sqlite3_stmt* s, std::size_t expected, const std::string& row) {
    if (sqlite3_column_int64(s, 0) != static_cast<sqlite3_int64>(expected)) {
      bad(row, "field id is not " + std::to_string(expected) + " (ids must be dense)");
    }
  }

  std::vector<KeyframeObservation> observations(sqlite3_stmt* s, int column,
                                                std::size_t landmark_count,
                                                const std::string& row) const {
    const auto bytes = static_cast<std::size_t>(sqlite3_column_bytes(s, column));
    if (bytes % kObservationBytes != 0) {
      bad(row, "field observations has " + std::to_string(bytes) + " bytes, not a multiple of 32");
    }
    const auto* data = static_cast<const char*>(sqlite3_column_blob(s, column));
    std::vector<KeyframeObservation> out(bytes / kObservationBytes);
    for (std::size_t i = 0; i < out.size(); ++i) {
      const char* p = data + i * kObservationBytes;
      double v[3];
      std::memcpy(&out[i].landmark_id, p, 8);
      std::memcpy(v, p + 8, 24);
      out[i].px = Eigen::Vector2d(v[0], v[1]);
      out[i].depth_m = v[2];
      if (out[i].landmark_id >= landmark_count) {
        bad(row, "field observations: landmark " + std::to_string(out[i].landmark_id) +
                     " does not exist (" + std::to_string(landmark_count) + " landmarks)");
      }
      if (!out[i].px.allFinite() || !std::isfinite(v[2]) || v[2] < 0.0) {
        bad(row, "field observations: observation " + std::to_string(i) + " is not finite");
      }
    }
    return out;
  }

  Db db_;
};

const std::string& required(const std::map<std::string, std::string>& meta, const std::string& key,
                            const Reader& reader) {
  const auto it = meta.find(key);
  if (it == meta.end()) reader.bad("meta." + key, "missing");
  return it->second;
}

double number(const std::map<std::string, std::string>& meta, const std::string& key,
              const Reader& reader) {
  const std::string& text = required(meta, key, reader);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v))
    reader.bad("meta." + key, "'" + text + "' is not a number");
  return v;
}

std::string shortNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.10g", v);
  return buf;
}

void checkVersionAndCamera(const std::map<std::string, std::string>& meta,
                           const PinholeCamera& camera, const Reader& reader) {
  const double version = number(meta, "format_version", reader);
  if (version != kMapFormatVersion) {
    reader.bad("meta.format_version", "version " + required(meta, "format_version", reader) +
                                          ", this dynamap reads version " +
                                          std::to_string(kMapFormatVersion));
  }
  const std::pair<const char*, double> expected[] = {
      {"camera.fx", camera.fx}, {"camera.fy", camera.fy},       {"camera.cx", camera.cx},
      {"camera.cy", camera.cy}, {"camera.width", camera.width}, {"camera.height", camera.height}};
  for (const auto& [key, value] : expected) {
    const double saved = number(meta, key, reader);
    if (std::abs(saved - value) > 1e-6 * std::max(1.0, std::abs(value))) {
      reader.bad(std::string("meta.") + key, "the map was made with " + shortNumber(saved) +
                                                 ", this camera has " + shortNumber(value));
    }
  }
}

void checkCount(const std::map<std::string, std::string>& meta, const std::string& table,
                std::size_t rows, const Reader& reader) {
  const double count = number(meta, table, reader);
  if (count != static_cast<double>(rows)) {
    reader.bad("table " + table, std::to_string(rows) + " rows, meta." + table + " says " +
                                     required(meta, table, reader) + " (truncated?)");
  }
}

}  // namespace

MapContents readMapStore(const std::string& path, const PinholeCamera& camera, MapStoreInfo* info) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw MapFileError(path + ": no such map file");
  Reader reader(path);
  const auto meta = reader.meta();
  checkVersionAndCamera(meta, camera, reader);
  MapContents contents;
  contents.landmarks = reader.landmarks();
  checkCount(meta, "landmarks", contents.landmarks.size(), reader);
  contents.keyframes = reader.keyframes(contents.landmarks.size());
  checkCount(meta, "keyframes", contents.keyframes.size(), reader);
  if (info != nullptr) info->backend = required(meta, "backend", reader);
  return contents;
}

}  // namespace dynamap
