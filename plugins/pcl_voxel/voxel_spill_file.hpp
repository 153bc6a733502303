#pragma once

// An unnamed temporary file (removed by the system when closed, even after a crash) holding
// keyframes' compact voxels once they leave the newest keyframes: RAM then holds the active
// keyframes only, and an export streams the others back (read() is safe on several threads at
// once: positioned reads, no shared file offset).

#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

#include "dynamap/mapping/map_backend.hpp"

namespace dynamap::plugin {

template <typename Record>
class SpillFile {
 public:
  struct Span {
    long long offset = 0;
    std::size_t count = 0;
  };

  SpillFile() : file_(std::tmpfile()) {
    if (!file_) throw MappingError("cannot create a temporary file for the map's keyframes");
  }
  ~SpillFile() { std::fclose(file_); }
  SpillFile(const SpillFile&) = delete;
  SpillFile& operator=(const SpillFile&) = delete;

  Span append(const std::vector<Record>& records) {
    Span span{end_, records.size()};
    if (fseeko(file_, end_, SEEK_SET) != 0 ||
        std::fwrite(records.data(), sizeof(Record), records.size(), file_) != records.size() ||
        std::fflush(file_) != 0) {
      throw MappingError("cannot write the map's keyframes to a temporary file (disk full?)");
    }
    end_ += static_cast<long long>(records.size() * sizeof(Record));
    return span;
  }

  void read(const Span& span, std::vector<Record>& out) const {
    out.resize(span.count);
    auto* bytes = reinterpret_cast<char*>(out.data());
    const std::size_t total = span.count * sizeof(Record);
    for (std::size_t done = 0; done < total;) {
      const ssize_t n = ::pread(fileno(file_), bytes + done, total - done,
                                static_cast<off_t>(span.offset + static_cast<long long>(done)));
      if (n <= 0) {
        throw MappingError("cannot read the map's keyframes back from their temporary file");
      }
      done += static_cast<std::size_t>(n);
    }
  }

  long long bytes() const { return end_; }

 private:
  std::FILE* file_;
  long long end_ = 0;
};

}  // namespace dynamap::plugin
