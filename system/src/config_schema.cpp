#include "dynamap/system/config_schema.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace dynamap {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  const auto e = s.find_last_not_of(" \t");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

std::string where(const std::string& origin, const YAML::Node& node) {
  if (node.Mark().is_null()) return origin;
  return origin + ":" + std::to_string(node.Mark().line + 1);
}

double parseDouble(const std::string& key, const std::string& value, const std::string& at) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || end != value.c_str() + value.size() || errno != 0 || !std::isfinite(v)) {
    throw ConfigError(at + ": key '" + key + "': expected a number, got '" + value + "'");
  }
  return v;
}

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    item = trim(item);
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

}  // namespace

void ConfigSchema::addDouble(const std::string& key, double* field, double min, double max) {
  Entry e;
  e.set_scalar = [key, field, min, max](const std::string& v, const std::string& at) {
    const double d = parseDouble(key, v, at);
    if (d < min || d > max) {
      std::ostringstream msg;
      msg << at << ": key '" << key << "': value " << v << " out of range [" << min << ", " << max
          << "]";
      throw ConfigError(msg.str());
    }
    *field = d;
  };
  e.get = [field] {
    std::ostringstream s;
    s.precision(10);
    s << *field;
    return s.str();
  };
  entries_[key] = std::move(e);
}

void ConfigSchema::addInt(const std::string& key, int* field, int min, int max) {
  Entry e;
  e.set_scalar = [key, field, min, max](const std::string& v, const std::string& at) {
    const double d = parseDouble(key, v, at);
    if (d != std::floor(d)) {
      throw ConfigError(at + ": key '" + key + "': expected an integer, got '" + v + "'");
    }
    if (d < min || d > max) {
      throw ConfigError(at + ": key '" + key + "': value " + v + " out of range [" +
                        std::to_string(min) + ", " + std::to_string(max) + "]");
    }
    *field = static_cast<int>(d);
  };
  e.get = [field] { return std::to_string(*field); };
  entries_[key] = std::move(e);
}

void ConfigSchema::addBool(const std::string& key, bool* field) {
  Entry e;
  e.set_scalar = [key, field](const std::string& v, const std::string& at) {
    std::string l = v;
    std::transform(l.begin(), l.end(), l.begin(), ::tolower);
    if (l == "true" || l == "1" || l == "yes" || l == "on") {
      *field = true;
    } else if (l == "false" || l == "0" || l == "no" || l == "off") {
      *field = false;
    } else {
      throw ConfigError(at + ": key '" + key + "': expected true/false, got '" + v + "'");
    }
  };
  e.get = [field] { return std::string(*field ? "true" : "false"); };
  entries_[key] = std::move(e);
}

void ConfigSchema::addString(const std::string& key, std::string* field,
                             std::vector<std::string> allowed) {
  Entry e;
  e.set_scalar = [key, field, allowed](const std::string& v, const std::string& at) {
    if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), v) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      throw ConfigError(at + ": key '" + key + "': '" + v + "' is not one of: " + list);
    }
    *field = v;
  };
  e.get = [field] { return *field; };
  entries_[key] = std::move(e);
}

void ConfigSchema::addStringList(const std::string& key, std::vector<std::string>* field) {
  Entry e;
  e.is_list = true;
  e.set_scalar = [field](const std::string& v, const std::string&) { *field = splitList(v); };
  e.set_list = [field](const std::vector<std::string>& v) { *field = v; };
  e.get = [field] {
    std::string s;
    for (const auto& x : *field) s += (s.empty() ? "" : ",") + x;
    return s;
  };
  entries_[key] = std::move(e);
}

void ConfigSchema::addStringMap(const std::string& prefix,
                                std::map<std::string, std::string>* field) {
  prefixes_[prefix] = field;
}

namespace {

// Free-form keys below a prefix (plugin parameters) are "<backend>.<name>": no empty parts
// ("a..b" would nest unnamed sections in the effective config) and at most kMaxSubKeyParts
// levels (yaml-cpp cannot read back maps nested hundreds deep).
constexpr int kMaxSubKeyParts = 4;

void checkSubKey(const std::string& key, const std::string& sub, const std::string& at) {
  int parts = 1;
  bool empty_part = sub.empty() || sub.front() == '.' || sub.back() == '.';
  for (std::size_t i = 0; i < sub.size(); ++i) {
    if (sub[i] != '.') continue;
    ++parts;
    empty_part = empty_part || (i + 1 < sub.size() && sub[i + 1] == '.');
  }
  if (empty_part) throw ConfigError(at + ": key '" + key + "' has an empty part ('..')");
  if (parts > kMaxSubKeyParts) {
    throw ConfigError(at + ": key '" + key + "' is nested deeper than " +
                      std::to_string(kMaxSubKeyParts) + " levels below its section");
  }
}

}  // namespace

void ConfigSchema::setValue(const std::string& key, const std::string& value,
                            const std::string& at) {
  auto it = entries_.find(key);
  if (it != entries_.end()) {
    it->second.set_scalar(value, at);
    return;
  }
  for (auto& [prefix, map] : prefixes_) {
    if (key.size() > prefix.size() + 1 && key.compare(0, prefix.size(), prefix) == 0 &&
        key[prefix.size()] == '.') {
      const std::string sub = key.substr(prefix.size() + 1);
      checkSubKey(key, sub, at);
      (*map)[sub] = value;
      return;
    }
  }
  throw ConfigError(at + ": unknown configuration key '" + key + "'");
}

void ConfigSchema::loadYamlString(const std::string& text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(origin + ":" + std::to_string(e.mark.line + 1) +
                      ": YAML syntax error: " + e.msg);
  }
  if (root.IsNull()) return;
  if (!root.IsMap()) throw ConfigError(origin + ": top level must be a mapping of sections");

  std::function<void(const YAML::Node&, const std::string&)> walk;
  walk = [&](const YAML::Node& node, const std::string& path) {
    for (const auto& kv : node) {
      const std::string name = kv.first.as<std::string>();
      const std::string key = path.empty() ? name : path + "." + name;
      const YAML::Node& value = kv.second;
      const std::string at = where(origin, kv.first);
      auto it = entries_.find(key);
      if (value.IsMap()) {
        walk(value, key);
      } else if (value.IsSequence()) {
        if (it == entries_.end() || !it->second.is_list) {
          throw ConfigError(at + ": key '" + key + "' does not take a list");
        }
        std::vector<std::string> items;
        for (const auto& item : value) {
          if (!item.IsScalar()) throw ConfigError(at + ": key '" + key + "': nested list");
          items.push_back(item.as<std::string>());
        }
        it->second.set_list(items);
      } else if (value.IsScalar()) {
        setValue(key, value.as<std::string>(), at);
      } else if (value.IsNull() && it == entries_.end()) {
        // An empty section ("mapping:") is allowed when something lives below it.
        bool known = prefixes_.count(key) > 0;
        for (const auto& [k, unused] : entries_) known = known || k.rfind(key + ".", 0) == 0;
        if (!known) throw ConfigError(at + ": unknown configuration key '" + key + "'");
      }
    }
  };
  try {
    walk(root, "");
  } catch (const YAML::Exception& e) {  // e.g. a key that is a map or a list
    throw ConfigError(origin + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

void ConfigSchema::loadYamlFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open configuration file");
  std::stringstream ss;
  ss << in.rdbuf();
  loadYamlString(ss.str(), path);
}

void ConfigSchema::applyOverride(const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw ConfigError("--set '" + assignment + "': expected section.key=value");
  }
  setValue(trim(assignment.substr(0, eq)), trim(assignment.substr(eq + 1)), "--set " + assignment);
}

std::vector<std::string> ConfigSchema::keys() const {
  std::vector<std::string> out;
  for (const auto& [k, unused] : entries_) out.push_back(k);
  return out;
}

namespace {

struct DumpTree {
  std::map<std::string, DumpTree> children;
  std::string scalar;
  std::vector<std::string> list;
  bool is_list = false;
};

void insertPath(DumpTree& root, const std::string& key, const DumpTree& leaf) {
  DumpTree* node = &root;
  std::stringstream ss(key);
  std::string part;
  while (std::getline(ss, part, '.')) node = &node->children[part];
  node->scalar = leaf.scalar;
  node->list = leaf.list;
  node->is_list = leaf.is_list;
}

// yaml-cpp writes some plain scalars it cannot read back (e.g. "b:\r"): quote those.
void emitScalar(YAML::Emitter& out, const std::string& s) {
  bool quote = !s.empty() && s.back() == ':';
  for (const unsigned char c : s) quote = quote || c < 0x20 || c == 0x7f;
  if (quote) out << YAML::DoubleQuoted;
  out << s;
}

void emitTree(YAML::Emitter& out, const DumpTree& node) {
  if (node.children.empty()) {
    if (node.is_list) {
      out << YAML::Flow << YAML::BeginSeq;
      for (const auto& item : node.list) emitScalar(out, item);
      out << YAML::EndSeq;
    } else {
      emitScalar(out, node.scalar);
    }
    return;
  }
  out << YAML::BeginMap;
  for (const auto& [name, child] : node.children) {
    // Implicit keys are limited to 1024 characters (escapes included): explicit "? key".
    if (name.size() > 128) out << YAML::LongKey;
    out << YAML::Key;
    emitScalar(out, name);
    out << YAML::Value;
    emitTree(out, child);
  }
  out << YAML::EndMap;
}

}  // namespace

std::string ConfigSchema::dumpYaml() const {
  DumpTree root;
  for (const auto& [key, entry] : entries_) {
    DumpTree leaf;
    leaf.is_list = entry.is_list;
    if (entry.is_list) {
      leaf.list = splitList(entry.get());
    } else {
      leaf.scalar = entry.get();
    }
    insertPath(root, key, leaf);
  }
  for (const auto& [prefix, map] : prefixes_) {
    for (const auto& [k, v] : *map) {
      DumpTree leaf;
      leaf.scalar = v;
      insertPath(root, prefix + "." + k, leaf);
    }
  }
  YAML::Emitter out;
  out.SetOutputCharset(YAML::EscapeNonAscii);  // invalid UTF-8 in a value stays loadable
  emitTree(out, root);
  return std::string(out.c_str()) + "\n";
}

}  // namespace dynamap
