#pragma once
// Helpers shared by the libFuzzer targets: the readers under test take file paths, so each
// input is written to a per-process scratch folder first.

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace dynamap::fuzz {

/// A folder of this process, removed at exit (left behind only after a crash).
inline const std::string& scratchDir() {
  // Never destroyed: the atexit cleanup runs after static destructors.
  static const std::string* const dir = [] {
    namespace fs = std::filesystem;
    const fs::path d = fs::temp_directory_path() / ("dynamap_fuzz_" + std::to_string(::getpid()));
    fs::create_directories(d);
    auto* path = new std::string(d.string());
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(scratchDir(), ec);
    });
    return path;
  }();
  return *dir;
}

/// Writes `bytes` to scratchDir()/name and returns the path.
inline std::string writeScratch(const std::string& name, const std::string& bytes) {
  const std::string path = scratchDir() + "/" + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

/// Splits `text` at each `separator` into at most `max_parts` parts (the last keeps the rest).
inline std::vector<std::string> splitParts(const std::string& text, const std::string& separator,
                                           std::size_t max_parts) {
  std::vector<std::string> parts;
  std::size_t begin = 0;
  while (parts.size() + 1 < max_parts) {
    const std::size_t at = text.find(separator, begin);
    if (at == std::string::npos) break;
    parts.push_back(text.substr(begin, at - begin));
    begin = at + separator.size();
  }
  parts.push_back(text.substr(begin));
  return parts;
}

/// Splits `text` into lines (no '\n').
inline std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out = splitParts(text, "\n", text.size() + 1);
  return out;
}

/// A broken property of a reader: print it and abort so libFuzzer keeps the input.
[[noreturn]] inline void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz property violated: %s\n", what.c_str());
  std::abort();
}

/// The part separator used by targets that read several files from one input.
inline constexpr const char* kSeparator = "\n====\n";

}  // namespace dynamap::fuzz
