#pragma once

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace dynamap {

/// A JSON document could not be parsed; the message names the source and the byte offset.
class JsonParseError : public std::runtime_error {
 public:
  using runtime_error::runtime_error;
};

/// A parsed JSON value (small documents: run.json, metrics.json, timings.json).
/// Objects keep their keys in file order. Immutable after parsing; thread-safe to read.
class JsonValue {
 public:
  enum class Type { kNull, kBool, kNumber, kString, kArray, kObject };

  Type type() const { return type_; }
  bool isObject() const { return type_ == Type::kObject; }
  bool isNumber() const { return type_ == Type::kNumber; }
  bool isString() const { return type_ == Type::kString; }

  /// Member `key` of an object, nullptr when absent or when this is not an object.
  const JsonValue* find(const std::string& key) const;
  /// Number of member `key`, or nullopt when absent / not a number (JSON null included).
  std::optional<double> number(const std::string& key) const;
  /// String of member `key`, or nullopt when absent / not a string.
  std::optional<std::string> string(const std::string& key) const;

  double asNumber() const { return number_; }
  bool asBool() const { return bool_; }
  const std::string& asString() const { return string_; }
  const std::vector<JsonValue>& items() const { return items_; }
  /// Object members in file order.
  const std::vector<std::pair<std::string, JsonValue>>& members() const { return members_; }

 private:
  friend class JsonParser;
  Type type_ = Type::kNull;
  bool bool_ = false;
  double number_ = 0.0;
  std::string string_;
  std::vector<JsonValue> items_;
  std::vector<std::pair<std::string, JsonValue>> members_;
};

/// Parses `text` (RFC 8259; \u escapes outside ASCII become UTF-8). `source` names the text in
/// error messages. Throws JsonParseError.
JsonValue parseJson(const std::string& text, const std::string& source = "json");

/// Reads and parses a JSON file. Throws JsonParseError naming the file (also when unreadable).
JsonValue readJsonFile(const std::string& path);

}  // namespace dynamap
