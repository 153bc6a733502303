#pragma once

#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace dynamap {

/// A configuration problem: unknown key, bad value, unreadable file. The message names the
/// file, line and key.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Binds dotted keys ("tracking.lk_levels") to typed fields whose defaults live in code.
/// YAML files and `--set key=value` overrides both go through it; unknown keys and
/// out-of-range values are errors naming the key. Not thread-safe; used at start-up only.
class ConfigSchema {
 public:
  void addDouble(const std::string& key, double* field, double min, double max);
  void addInt(const std::string& key, int* field, int min, int max);
  void addBool(const std::string& key, bool* field);
  /// `allowed` empty = any string.
  void addString(const std::string& key, std::string* field, std::vector<std::string> allowed = {});
  /// A YAML sequence of scalars, or a comma-separated string on the command line.
  void addStringList(const std::string& key, std::vector<std::string>* field);
  /// Free-form keys below `prefix` (e.g. plugin parameters): "prefix.a.b: v" ->
  /// (*field)["a.b"]="v". Whoever consumes them validates them.
  void addStringMap(const std::string& prefix, std::map<std::string, std::string>* field);

  /// Applies a YAML file on top of the current values. Throws ConfigError.
  void loadYamlFile(const std::string& path);
  /// Applies a YAML document given as text (`origin` names it in errors). Throws ConfigError.
  void loadYamlString(const std::string& text, const std::string& origin);
  /// Applies one "section.key=value" override. Throws ConfigError.
  void applyOverride(const std::string& assignment);

  /// The effective configuration as YAML (every key, current values).
  std::string dumpYaml() const;
  std::vector<std::string> keys() const;

 private:
  struct Entry {
    std::function<void(const std::string& value, const std::string& where)> set_scalar;
    std::function<void(const std::vector<std::string>& values)> set_list;  // may be empty
    std::function<std::string()> get;
    bool is_list = false;
  };
  void setValue(const std::string& key, const std::string& value, const std::string& where);
  std::map<std::string, Entry> entries_;
  std::map<std::string, std::map<std::string, std::string>*> prefixes_;
};

}  // namespace dynamap
