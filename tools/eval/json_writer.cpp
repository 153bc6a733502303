#include "json_writer.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace dynamap {

std::string jsonString(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof(buffer), "\\u%04x", static_cast<unsigned char>(c));
          out += buffer;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

std::string jsonNumber(double value) {
  if (!std::isfinite(value)) return "null";
  char buffer[40];
  for (int precision = 15; precision <= 17; ++precision) {
    std::snprintf(buffer, sizeof(buffer), "%.*g", precision, value);
    if (std::strtod(buffer, nullptr) == value) break;
  }
  return buffer;
}

JsonObject& JsonObject::add(const std::string& key, double value) {
  return addRaw(key, jsonNumber(value));
}
JsonObject& JsonObject::add(const std::string& key, int value) {
  return addRaw(key, std::to_string(value));
}
JsonObject& JsonObject::add(const std::string& key, std::int64_t value) {
  return addRaw(key, std::to_string(value));
}
JsonObject& JsonObject::add(const std::string& key, std::uint64_t value) {
  return addRaw(key, std::to_string(value));
}
JsonObject& JsonObject::add(const std::string& key, bool value) {
  return addRaw(key, value ? "true" : "false");
}
JsonObject& JsonObject::add(const std::string& key, const std::string& value) {
  return addRaw(key, jsonString(value));
}
JsonObject& JsonObject::add(const std::string& key, const char* value) {
  return addRaw(key, jsonString(value));
}
JsonObject& JsonObject::add(const std::string& key, const JsonObject& value) {
  members_.push_back({key, {}, {value}});
  return *this;
}
JsonObject& JsonObject::addRaw(const std::string& key, const std::string& json) {
  members_.push_back({key, json, {}});
  return *this;
}

std::string JsonObject::str(int indent) const { return render(indent, 0); }

std::string JsonObject::render(int indent, int level) const {
  if (members_.empty()) return "{}";
  const bool pretty = indent >= 0;
  const std::string inner = pretty ? std::string((level + 1) * indent, ' ') : "";
  const std::string outer = pretty ? std::string(level * indent, ' ') : "";
  std::string out = pretty ? "{\n" : "{";
  for (std::size_t i = 0; i < members_.size(); ++i) {
    const Member& m = members_[i];
    out += inner + jsonString(m.key) + (pretty ? ": " : ":");
    out += m.object.empty() ? m.raw : m.object.front().render(indent, level + 1);
    if (i + 1 < members_.size()) out += ",";
    if (pretty) out += "\n";
  }
  return out + outer + "}";
}

}  // namespace dynamap
