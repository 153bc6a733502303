#include "octree_file.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "dynamap/mapping/map_backend.hpp"

namespace dynamap::plugin {
namespace {

constexpr unsigned kTreeDepth = 16;                    // OcTree's levels below the root
constexpr std::size_t kNodeBytes = sizeof(float) + 1;  // log-odds, child bits

/// Errors name the file, the field and what is wrong.
class OtReader {
 public:
  explicit OtReader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void bad(const std::string& field, const std::string& what) const {
    throw MappingError(path_ + ": " + field + ": " + what);
  }

  std::string readBytes() const {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path_, ec)) bad("file", "no such file");
    std::ifstream in(path_, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    if (!in) bad("file", "cannot read");
    return bytes.str();
  }

  struct Header {
    std::string id;
    std::size_t size = 0;
    double res = 0.0;
    std::size_t data_offset = 0;
  };

  /// The text lines up to "data" (comments start with '#').
  Header header(const std::string& bytes) const {
    std::istringstream in(bytes);
    std::string line;
    if (!std::getline(in, line) || line.rfind("# Octomap OcTree file", 0) != 0) {
      bad("header", "not an OctoMap .ot file (first line)");
    }
    Header h;
    bool have_size = false, have_res = false;
    while (std::getline(in, line) && line != "data") {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream fields(line);
      std::string key;
      fields >> key;
      if (key == "id") {
        fields >> h.id;
      } else if (key == "size") {
        have_size = static_cast<bool>(fields >> h.size);
      } else if (key == "res") {
        have_res = static_cast<bool>(fields >> h.res);
      } else {
        bad("header", "unknown line '" + line.substr(0, 40) + "'");
      }
      if (!fields) bad("header " + key, "not readable");
    }
    if (line != "data") bad("header", "no 'data' line");
    if (h.id != "OcTree") bad("header id", "'" + h.id + "', not OcTree");
    if (!have_size) bad("header size", "missing");
    if (!have_res || !(h.res > 0.0)) bad("header res", "missing or not > 0");
    const std::streamoff at = in.tellg();  // -1 when "data" ended the file
    h.data_offset = at < 0 ? bytes.size() : static_cast<std::size_t>(at);
    return h;
  }

  /// Walks the node stream from `p`; returns the nodes seen.
  std::size_t checkNodes(const char* begin, const char* end) const {
    const char* p = begin;
    std::size_t nodes = 0;
    walk(p, end, 0, nodes);
    if (p != end) bad("data", std::to_string(end - p) + " bytes after the last node");
    return nodes;
  }

  static std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.10g", v);
    return buf;
  }

 private:
  void walk(const char*& p, const char* end, unsigned depth, std::size_t& nodes) const {
    const std::string field = "data: node " + std::to_string(nodes);
    if (static_cast<std::size_t>(end - p) < kNodeBytes) bad(field, "truncated");
    float log_odds = 0.0f;
    std::memcpy(&log_odds, p, sizeof(float));
    const auto children = static_cast<unsigned char>(p[sizeof(float)]);
    p += kNodeBytes;
    ++nodes;
    if (!std::isfinite(log_odds)) bad(field, "log-odds not finite");
    if (children != 0 && depth == kTreeDepth) bad(field, "children below the finest level");
    for (int i = 0; i < 8; ++i) {
      if (children & (1u << i)) walk(p, end, depth + 1, nodes);
    }
  }

  std::string path_;
};

}  // namespace

std::unique_ptr<octomap::OcTree> readOcTreeFile(const std::string& path, double resolution_m) {
  const OtReader reader(path);
  const std::string bytes = reader.readBytes();
  const OtReader::Header h = reader.header(bytes);
  if (std::abs(h.res - resolution_m) > 1e-6 * resolution_m) {
    reader.bad("header res", "the map was made with " + OtReader::number(h.res) +
                                 " m, this run's octomap.resolution_m is " +
                                 OtReader::number(resolution_m));
  }
  auto tree = std::make_unique<octomap::OcTree>(resolution_m);
  const char* data = bytes.data() + h.data_offset;
  const char* end = bytes.data() + bytes.size();
  if (h.size == 0 && data == end) return tree;  // an empty tree has no node stream
  const std::size_t nodes = reader.checkNodes(data, end);
  if (nodes != h.size) {
    reader.bad("header size",
               std::to_string(h.size) + " nodes, the data holds " + std::to_string(nodes));
  }
  std::istringstream stream(std::string(data, end));
  tree->readData(stream);
  return tree;
}

}  // namespace dynamap::plugin
