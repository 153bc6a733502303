#pragma once

#include <cstdlib>
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

/// Real-data tests need ../shared. Without it they skip on a developer's machine, and fail where
/// the environment says CI (CI=true, as .ci/run sets it) or DYNAMAP_REQUIRE_DATA=1: a CI run
/// without its data must not pass on skipped tests.
inline bool sharedDataRequired() {
  for (const char* name : {"CI", "DYNAMAP_REQUIRE_DATA"}) {
    const char* value = std::getenv(name);
    if (value != nullptr && *value != '\0' && std::string(value) != "0" &&
        std::string(value) != "false") {
      return true;
    }
  }
  return false;
}

}  // namespace dynamap::test

#define DYNAMAP_REQUIRE_SHARED_DATA()                                                          \
  do {                                                                                         \
    if (!std::filesystem::exists(::dynamap::test::sharedData())) {                             \
      if (::dynamap::test::sharedDataRequired()) {                                             \
        FAIL() << "../shared/data not found beside the checkout (required here): "             \
               << DYNAMAP_SHARED_DIR;                                                          \
      }                                                                                        \
      GTEST_SKIP() << "../shared/data not found beside the checkout: " << DYNAMAP_SHARED_DIR; \
    }                                                                                          \
  } while (0)
