#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace dynamap {

/// JSON string literal (quoted, escaped) of `text`.
std::string jsonString(const std::string& text);
/// JSON number: shortest decimal that reads back to the same double; NaN/inf -> null.
std::string jsonNumber(double value);

/// A JSON object built member by member, in insertion order. Not thread-safe.
///   JsonObject o; o.add("pairs", 12).add("rmse_m", 0.01); o.str();
class JsonObject {
 public:
  JsonObject& add(const std::string& key, double value);
  JsonObject& add(const std::string& key, int value);
  JsonObject& add(const std::string& key, std::int64_t value);
  JsonObject& add(const std::string& key, std::uint64_t value);
  JsonObject& add(const std::string& key, bool value);
  JsonObject& add(const std::string& key, const std::string& value);
  JsonObject& add(const std::string& key, const char* value);
  JsonObject& add(const std::string& key, const JsonObject& value);
  /// `json` is inserted verbatim (caller guarantees it is valid JSON).
  JsonObject& addRaw(const std::string& key, const std::string& json);

  bool empty() const { return members_.empty(); }
  /// indent < 0: one line; otherwise pretty-printed with `indent` spaces per level.
  std::string str(int indent = -1) const;

 private:
  std::string render(int indent, int level) const;
  // Members whose value is an object keep it so pretty-printing can nest.
  struct Member {
    std::string key;
    std::string raw;
    std::vector<JsonObject> object;  // 0 or 1 element
  };
  std::vector<Member> members_;
};

}  // namespace dynamap
