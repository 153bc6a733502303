#include "dynamap/mapping/ply_io.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "dynamap/mapping/map_backend.hpp"

namespace dynamap {
namespace {

struct Property {
  std::string name;
  std::string type;        // scalar type, or the list's item type
  std::string count_type;  // non-empty for list properties
};
struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> props;
};

std::size_t typeSize(const std::string& t, const std::string& path) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32")
    return 4;
  if (t == "double" || t == "float64") return 8;
  throw MappingError(path + ": unknown PLY type '" + t + "'");
}

// Decodes one little-endian scalar of PLY type t at p.
double decode(const char* p, const std::string& t) {
  auto as = [p](auto v) {
    std::memcpy(&v, p, sizeof(v));
    return static_cast<double>(v);
  };
  if (t == "float" || t == "float32") return as(float{});
  if (t == "uchar" || t == "uint8") return as(std::uint8_t{});
  if (t == "char" || t == "int8") return as(std::int8_t{});
  if (t == "short" || t == "int16") return as(std::int16_t{});
  if (t == "ushort" || t == "uint16") return as(std::uint16_t{});
  if (t == "int" || t == "int32") return as(std::int32_t{});
  if (t == "uint" || t == "uint32") return as(std::uint32_t{});
  return as(double{});
}

// Bytes after the current read position (the most any element can still hold).
std::uintmax_t remainingBytes(std::istream& in) {
  const std::streampos here = in.tellg();
  in.seekg(0, std::ios::end);
  const std::streampos end = in.tellg();
  in.seekg(here);
  if (here < 0 || end < here) return 0;
  return static_cast<std::uintmax_t>(end - here);
}

// A colour value of any PLY type as a byte (clamped; NaN -> 0).
std::uint8_t toByte(double v) {
  if (!(v > 0.0)) return 0;
  return v < 255.0 ? static_cast<std::uint8_t>(v) : std::uint8_t{255};
}

double readBinary(std::istream& in, const std::string& t, const std::string& path) {
  char buf[8];
  if (!in.read(buf, static_cast<std::streamsize>(typeSize(t, path)))) {
    throw MappingError(path + ": truncated PLY data");
  }
  return decode(buf, t);
}

std::vector<Element> readHeader(std::istream& in, const std::string& path, bool* binary) {
  std::string line;
  if (!std::getline(in, line) || line.rfind("ply", 0) != 0) {
    throw MappingError(path + ": not a PLY file");
  }
  std::vector<Element> elements;
  *binary = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "format") {
      std::string fmt;
      ls >> fmt;
      if (fmt == "binary_little_endian") {
        *binary = true;
      } else if (fmt != "ascii") {
        throw MappingError(path + ": unsupported PLY format '" + fmt + "'");
      }
    } else if (word == "element") {
      Element e;
      ls >> e.name >> e.count;
      elements.push_back(e);
    } else if (word == "property" && !elements.empty()) {
      Property p;
      std::string t;
      ls >> t;
      if (t == "list") {
        ls >> p.count_type >> p.type >> p.name;
      } else {
        p.type = t;
        ls >> p.name;
      }
      elements.back().props.push_back(p);
    } else if (word == "end_header") {
      return elements;
    }
  }
  throw MappingError(path + ": PLY header without end_header");
}

// Binary vertices without list properties: read the whole block, decode by byte offsets.
bool readFixedVertices(std::istream& in, const Element& e, const std::string& path,
                       const std::array<int, 6>& idx, PlyData* data) {
  std::vector<std::size_t> offset(e.props.size());
  std::size_t stride = 0;
  for (std::size_t k = 0; k < e.props.size(); ++k) {
    if (!e.props[k].count_type.empty()) return false;
    offset[k] = stride;
    stride += typeSize(e.props[k].type, path);
  }
  if (stride == 0 || e.count > remainingBytes(in) / stride) {
    throw MappingError(path + ": truncated PLY data");
  }
  std::vector<char> block(stride * e.count);
  if (!in.read(block.data(), static_cast<std::streamsize>(block.size()))) {
    throw MappingError(path + ": truncated PLY data");
  }
  auto value = [&](const char* rec, int k) {
    const auto ku = static_cast<std::size_t>(k);
    return decode(rec + offset[ku], e.props[ku].type);
  };
  const bool colours = idx[3] >= 0 && idx[4] >= 0 && idx[5] >= 0;
  for (std::size_t i = 0; i < e.count; ++i) {
    const char* rec = block.data() + i * stride;
    data->vertices.emplace_back(value(rec, idx[0]), value(rec, idx[1]), value(rec, idx[2]));
    if (colours) {
      data->colors.push_back(
          {toByte(value(rec, idx[3])), toByte(value(rec, idx[4])), toByte(value(rec, idx[5]))});
    }
  }
  return true;
}

}  // namespace

PlyData readPly(const std::string& path, bool with_faces) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MappingError(path + ": cannot open PLY file");
  bool binary = false;
  const std::vector<Element> elements = readHeader(in, path, &binary);
  PlyData data;
  if (std::count_if(elements.begin(), elements.end(),
                    [](const Element& e) { return e.name == "vertex"; }) > 1) {
    throw MappingError(path + ": PLY file with more than one vertex element");
  }
  for (const Element& e : elements) {
    const bool is_vertex = e.name == "vertex";
    const bool is_face = e.name == "face" && with_faces;
    int ix = -1, iy = -1, iz = -1, ir = -1, ig = -1, ib = -1;
    for (std::size_t k = 0; k < e.props.size(); ++k) {
      const std::string& n = e.props[k].name;
      const int ki = static_cast<int>(k);
      if (n == "x") ix = ki;
      if (n == "y") iy = ki;
      if (n == "z") iz = ki;
      if (n == "red" || n == "r") ir = ki;
      if (n == "green" || n == "g") ig = ki;
      if (n == "blue" || n == "b") ib = ki;
    }
    if (is_vertex && (ix < 0 || iy < 0 || iz < 0)) {
      throw MappingError(path + ": PLY vertices without x, y, z");
    }
    const bool colours = is_vertex && ir >= 0 && ig >= 0 && ib >= 0;
    if (e.props.empty()) continue;  // no data in the file
    // Every element takes at least one byte: a larger count is a corrupt header.
    const std::uintmax_t available = remainingBytes(in);
    if (e.count > available) {
      throw MappingError(path + ": PLY element '" + e.name + "' count " + std::to_string(e.count) +
                         " exceeds the file size");
    }
    if (is_vertex) data.vertices.reserve(e.count);
    if (binary && is_vertex && readFixedVertices(in, e, path, {ix, iy, iz, ir, ig, ib}, &data)) {
      continue;
    }
    std::vector<double> values(e.props.size());
    std::vector<double> list;
    for (std::size_t i = 0; i < e.count; ++i) {
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        const Property& p = e.props[k];
        if (p.count_type.empty()) {
          if (binary) {
            values[k] = readBinary(in, p.type, path);
          } else if (!(in >> values[k])) {
            throw MappingError(path + ": truncated PLY data");
          }
          continue;
        }
        double n = 0;
        if (binary) {
          n = readBinary(in, p.count_type, path);
        } else if (!(in >> n)) {
          throw MappingError(path + ": truncated PLY data");
        }
        if (!(n >= 0.0 && n <= static_cast<double>(available))) {
          throw MappingError(path + ": bad PLY list length " + std::to_string(n));
        }
        list.resize(static_cast<std::size_t>(n));
        for (double& v : list) {
          if (binary) {
            v = readBinary(in, p.type, path);
          } else if (!(in >> v)) {
            throw MappingError(path + ": truncated PLY data");
          }
        }
        if (is_face) {
          for (const double v : list) {
            if (!(v >= 0.0 && v < 4294967296.0)) {
              throw MappingError(path + ": bad PLY face index " + std::to_string(v));
            }
          }
          for (std::size_t t = 1; t + 1 < list.size(); ++t) {  // fan-triangulate polygons
            data.triangles.push_back({static_cast<std::uint32_t>(list[0]),
                                      static_cast<std::uint32_t>(list[t]),
                                      static_cast<std::uint32_t>(list[t + 1])});
          }
        }
      }
      if (is_vertex) {
        data.vertices.emplace_back(values[ix], values[iy], values[iz]);
        if (colours) {
          data.colors.push_back({toByte(values[ir]), toByte(values[ig]), toByte(values[ib])});
        }
      }
    }
  }
  for (const auto& t : data.triangles) {
    if (t[0] >= data.vertices.size() || t[1] >= data.vertices.size() ||
        t[2] >= data.vertices.size()) {
      throw MappingError(path + ": PLY face index out of range (" +
                         std::to_string(data.vertices.size()) + " vertices)");
    }
  }
  return data;
}

void writePly(const std::string& path, const PlyData& data) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw MappingError(path + ": cannot write PLY file");
  const bool colours = !data.colors.empty() && data.colors.size() == data.vertices.size();
  out << "ply\nformat binary_little_endian 1.0\ncomment dynamap\n"
      << "element vertex " << data.vertices.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n";
  if (colours) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (!data.triangles.empty()) {
    out << "element face " << data.triangles.size() << "\n"
        << "property list uchar int vertex_indices\n";
  }
  out << "end_header\n";
  // Records are packed into one buffer and written in large blocks (a write per vertex cost more
  // than the bytes).
  const std::size_t vertex_bytes = 3 * sizeof(float) + (colours ? 3 : 0);
  constexpr std::size_t kFaceBytes = 1 + 3 * sizeof(std::int32_t);
  constexpr std::size_t kBlockRecords = 1 << 16;
  std::vector<char> block;
  const auto put = [&block](const void* bytes, std::size_t n) {
    const auto* c = static_cast<const char*>(bytes);
    block.insert(block.end(), c, c + n);
  };
  const auto flush = [&] {
    out.write(block.data(), static_cast<std::streamsize>(block.size()));
    block.clear();
  };
  block.reserve(kBlockRecords * std::max(vertex_bytes, kFaceBytes));
  for (std::size_t i = 0; i < data.vertices.size(); ++i) {
    put(data.vertices[i].data(), 3 * sizeof(float));
    if (colours) put(data.colors[i].data(), 3);
    if ((i + 1) % kBlockRecords == 0) flush();
  }
  flush();
  for (std::size_t i = 0; i < data.triangles.size(); ++i) {
    const auto& t = data.triangles[i];
    const std::uint8_t n = 3;
    put(&n, 1);
    const std::int32_t idx[3] = {static_cast<std::int32_t>(t[0]), static_cast<std::int32_t>(t[1]),
                                 static_cast<std::int32_t>(t[2])};
    put(idx, sizeof(idx));
    if ((i + 1) % kBlockRecords == 0) flush();
  }
  flush();
  if (!out) throw MappingError(path + ": write failed");
}

void writeAtomically(const std::string& final_path,
                     const std::function<void(const std::string& tmp_path)>& write) {
  namespace fs = std::filesystem;
  const fs::path target(final_path);
  std::error_code ec;
  if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
  const fs::path tmp = target.parent_path() /
                       ("." + target.filename().string() + ".tmp" + std::to_string(::getpid()));
  try {
    write(tmp.string());
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  if (!fs::exists(tmp, ec)) throw MappingError(final_path + ": writer produced no file");
  fs::rename(tmp, target, ec);
  if (ec) throw MappingError(final_path + ": rename failed: " + ec.message());
}

}  // namespace dynamap
