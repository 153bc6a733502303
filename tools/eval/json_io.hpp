#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace dynamap {

/// JSON documents of a run (run.json, metrics.json, timings.json): nlohmann-json, objects keep
/// their keys in insertion / file order.
using Json = nlohmann::ordered_json;

/// Reads and parses a JSON file. Throws std::runtime_error "<path>: invalid JSON at byte N (...)",
/// "<path>: invalid JSON (...)" (a number out of range) or "<path>: cannot open"; nothing else.
Json readJsonFile(const std::string& path);

/// Text of `json`: one line (indent < 0) or pretty with `indent` spaces. NaN and infinities
/// become null; invalid UTF-8 in strings is replaced (U+FFFD), never an exception.
std::string dumpJson(const Json& json, int indent = -1);

/// Member `key` of an object; nullptr when absent or when `object` is not an object.
const Json* findMember(const Json& object, const std::string& key);
/// Number of member `key`; nullopt when absent or not a number (null included).
std::optional<double> numberMember(const Json& object, const std::string& key);
/// String of member `key`; nullopt when absent or not a string.
std::optional<std::string> stringMember(const Json& object, const std::string& key);

}  // namespace dynamap
