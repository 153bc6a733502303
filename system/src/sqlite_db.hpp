#pragma once

// The map store's SQLite connection (system/src only): every failure is a MapFileError.

#include <memory>
#include <string>

#include <sqlite3.h>

#include "dynamap/system/map_store.hpp"

namespace dynamap {

inline constexpr std::size_t kObservationBytes = 32;  // landmark id u64, u v f64, depth_m f64
inline constexpr int kDescriptorBytes = 32;

/// One SQLite connection; every failure is a MapFileError naming the file.
class Db {
 public:
  Db(const std::string& path, int flags) : path_(path) {
    if (sqlite3_open_v2(path.c_str(), &db_, flags, nullptr) != SQLITE_OK) fail("cannot open");
  }
  ~Db() { sqlite3_close(db_); }
  Db(const Db&) = delete;
  Db& operator=(const Db&) = delete;

  [[noreturn]] void fail(const std::string& what) const {
    throw MapFileError(path_ + ": " + what + " (sqlite: " + sqlite3_errmsg(db_) + ")");
  }
  void exec(const char* sql) {
    if (sqlite3_exec(db_, sql, nullptr, nullptr, nullptr) != SQLITE_OK) fail(sql);
  }
  /// A prepared statement, finalised with its owner.
  using Statement = std::unique_ptr<sqlite3_stmt, int (*)(sqlite3_stmt*)>;
  Statement prepare(const char* sql, const std::string& what) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db_, sql, -1, &stmt, nullptr) != SQLITE_OK) fail(what);
    return Statement(stmt, sqlite3_finalize);
  }
  /// sqlite3_step; true while a row is there.
  bool step(sqlite3_stmt* stmt, const std::string& what) {
    const int rc = sqlite3_step(stmt);
    if (rc == SQLITE_ROW) return true;
    if (rc != SQLITE_DONE) fail(what);
    return false;
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  sqlite3* db_ = nullptr;
};

}  // namespace dynamap
