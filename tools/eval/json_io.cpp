#include "json_io.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace dynamap {

Json readJsonFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  try {
    return Json::parse(text.str());
  } catch (const Json::parse_error& e) {
    throw std::runtime_error(path + ": invalid JSON at byte " + std::to_string(e.byte) + " (" +
                             e.what() + ")");
  } catch (const Json::exception& e) {  // e.g. out_of_range: a number like 1e400 overflows
    throw std::runtime_error(path + ": invalid JSON (" + e.what() + ")");
  }
}

std::string dumpJson(const Json& json, int indent) {
  return json.dump(indent, ' ', false, Json::error_handler_t::replace);
}

const Json* findMember(const Json& object, const std::string& key) {
  if (!object.is_object()) return nullptr;
  const auto it = object.find(key);
  return it == object.end() ? nullptr : &*it;
}

std::optional<double> numberMember(const Json& object, const std::string& key) {
  const Json* v = findMember(object, key);
  if (v == nullptr || !v->is_number()) return std::nullopt;
  return v->get<double>();
}

std::optional<std::string> stringMember(const Json& object, const std::string& key) {
  const Json* v = findMember(object, key);
  if (v == nullptr || !v->is_string()) return std::nullopt;
  return v->get<std::string>();
}

}  // namespace dynamap
