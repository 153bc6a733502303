#include "dynamap/system/atomic_file.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace dynamap {

void writeBytesAtomic(const std::string& path, const char* data, std::size_t size) {
  const std::string tmp_path = path + ".tmp";
  {
    std::ofstream out(tmp_path, std::ios::binary | std::ios::trunc);
    if (!out) {
      throw std::runtime_error("cannot write " + tmp_path + ": " + std::strerror(errno));
    }
    out.write(data, static_cast<std::streamsize>(size));
    out.flush();
    if (!out) {
      throw std::runtime_error("error while writing " + tmp_path);
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp_path, path, ec);
  if (ec) {
    std::filesystem::remove(tmp_path, ec);
    throw std::runtime_error("cannot rename " + tmp_path + " to " + path);
  }
}

void writeTextFileAtomic(const std::string& path, const std::string& content) {
  writeBytesAtomic(path, content.data(), content.size());
}

}  // namespace dynamap
