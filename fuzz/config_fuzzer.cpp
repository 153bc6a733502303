// libFuzzer target: the configuration readers (ConfigSchema YAML + --set overrides through
// loadAppConfig). Input: YAML text, then "\n====\n", then one override per line. Only
// ConfigError may come out, and the effective YAML of an accepted config must load again.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "dynamap/system/app_config.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::vector<std::string> parts =
      dynamap::fuzz::splitParts(text, dynamap::fuzz::kSeparator, 2);
  const std::string path = dynamap::fuzz::writeScratch("config.yaml", parts[0]);
  std::vector<std::string> overrides;
  if (parts.size() > 1) {
    for (const std::string& line : dynamap::fuzz::lines(parts[1])) {
      if (!line.empty()) overrides.push_back(line);
    }
  }
  std::string effective;
  try {
    (void)dynamap::loadAppConfig(path, overrides, &effective);
  } catch (const dynamap::ConfigError&) {
    return 0;
  }
  // What a run writes as config.yaml must be accepted as a config file.
  dynamap::ConfigSchema schema;
  dynamap::AppConfig again;
  dynamap::bindAppConfig(schema, again);
  try {
    schema.loadYamlString(effective, "effective config");
  } catch (const dynamap::ConfigError& e) {
    dynamap::fuzz::fail(std::string("effective config does not load again: ") + e.what());
  }
  return 0;
}
