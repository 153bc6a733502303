#pragma once

#include <cstddef>
#include <string>

namespace dynamap {

/// Writes `content` to path + ".tmp" and renames it onto `path`, so readers never see a
/// half-written file. Throws std::runtime_error naming the path on failure.
void writeTextFileAtomic(const std::string& path, const std::string& content);

/// Same for bytes.
void writeBytesAtomic(const std::string& path, const char* data, std::size_t size);

}  // namespace dynamap
