#pragma once

#include <set>
#include <string>

#include "dynamap/mapping/map_backend.hpp"

namespace dynamap {

/// Typed, validated access to a backend's free-form parameters. Every getter removes the key from
/// the unread set; finish() throws MappingError naming the first key nobody asked for. Bad values
/// throw MappingError naming "mapping.params.<backend>.<key>".
class ParamReader {
 public:
  ParamReader(std::string backend, const BackendParams& params);
  double getDouble(const std::string& key, double fallback, double min, double max);
  int getInt(const std::string& key, int fallback, int min, int max);
  bool getBool(const std::string& key, bool fallback);
  std::string getString(const std::string& key, const std::string& fallback,
                        const std::set<std::string>& allowed);
  void finish() const;

 private:
  const std::string* find(const std::string& key);
  std::string fullKey(const std::string& key) const;
  std::string backend_;
  BackendParams params_;
  std::set<std::string> unread_;
};

}  // namespace dynamap
