#include "dynamap/mapping/backend_params.hpp"

#include <cstdlib>
#include <sstream>

namespace dynamap {

ParamReader::ParamReader(std::string backend, const BackendParams& params)
    : backend_(std::move(backend)), params_(params) {
  for (const auto& kv : params_) unread_.insert(kv.first);
}

std::string ParamReader::fullKey(const std::string& key) const {
  return "mapping.params." + backend_ + "." + key;
}

const std::string* ParamReader::find(const std::string& key) {
  unread_.erase(key);
  const auto it = params_.find(key);
  return it == params_.end() ? nullptr : &it->second;
}

double ParamReader::getDouble(const std::string& key, double fallback, double min, double max) {
  const std::string* text = find(key);
  if (text == nullptr) return fallback;
  char* end = nullptr;
  const double v = std::strtod(text->c_str(), &end);
  if (text->empty() || *end != '\0' || !(v >= min && v <= max)) {
    std::ostringstream msg;
    msg << fullKey(key) << ": bad value '" << *text << "' (expected a number in [" << min << ", "
        << max << "])";
    throw MappingError(msg.str());
  }
  return v;
}

int ParamReader::getInt(const std::string& key, int fallback, int min, int max) {
  const std::string* text = find(key);
  if (text == nullptr) return fallback;
  char* end = nullptr;
  const long v = std::strtol(text->c_str(), &end, 10);
  if (text->empty() || *end != '\0' || v < min || v > max) {
    std::ostringstream msg;
    msg << fullKey(key) << ": bad value '" << *text << "' (expected an integer in [" << min << ", "
        << max << "])";
    throw MappingError(msg.str());
  }
  return static_cast<int>(v);
}

bool ParamReader::getBool(const std::string& key, bool fallback) {
  const std::string* text = find(key);
  if (text == nullptr) return fallback;
  if (*text == "true" || *text == "1" || *text == "yes" || *text == "on") return true;
  if (*text == "false" || *text == "0" || *text == "no" || *text == "off") return false;
  throw MappingError(fullKey(key) + ": bad value '" + *text + "' (expected true or false)");
}

std::string ParamReader::getString(const std::string& key, const std::string& fallback,
                                   const std::set<std::string>& allowed) {
  const std::string* text = find(key);
  if (text == nullptr) return fallback;
  if (!allowed.empty() && allowed.count(*text) == 0) {
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    throw MappingError(fullKey(key) + ": bad value '" + *text + "' (expected one of: " + list +
                       ")");
  }
  return *text;
}

void ParamReader::finish() const {
  if (unread_.empty()) return;
  throw MappingError(fullKey(*unread_.begin()) + ": unknown parameter of backend '" + backend_ +
                     "'");
}

}  // namespace dynamap
