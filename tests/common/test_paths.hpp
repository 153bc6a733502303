#pragma once

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace dynamap::test {

/// ../shared/data beside the checkout.
inline std::filesystem::path sharedData() {
  return std::filesystem::path(DYNAMAP_SHARED_DIR) / "data";
}
inline std::filesystem::path sharedModels() {
  return std::filesystem::path(DYNAMAP_SHARED_DIR) / "models";
}
inline std::filesystem::path sourceDir() { return DYNAMAP_SOURCE_DIR; }
inline std::filesystem::path binaryDir() { return DYNAMAP_BINARY_DIR; }

/// A fresh empty temporary folder for one test.
inline std::filesystem::path freshTempDir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("dynamap_test_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace dynamap::test

/// Real-data tests need ../shared; CI always has it.
#define DYNAMAP_REQUIRE_SHARED_DATA()                                                         \
  do {                                                                                        \
    if (!std::filesystem::exists(::dynamap::test::sharedData())) {                            \
      GTEST_SKIP() << "../shared/data not found beside the checkout: " << DYNAMAP_SHARED_DIR; \
    }                                                                                         \
  } while (0)
