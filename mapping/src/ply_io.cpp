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
#include "dynamap/mapping/ply_header.hpp"

namespace dynamap {
namespace {

std::size_t typeSize(const std::string& t, const std::string& path) {
  const std::size_t size = plyScalarSize(t);
  if (size == 0) throw MappingError(path + ": unknown PLY type '" + t + "'");
  return size;
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

// Reads one value of the data section, ASCII or binary.
struct ValueReader {
  std::istream& in;
  const std::string& path;
  bool binary;

  double next(const std::string& type) {
    if (binary) {
      char buf[8];
      if (!in.read(buf, static_cast<std::streamsize>(typeSize(type, path)))) {
        throw MappingError(path + ": truncated PLY data");
      }
      return decode(buf, type);
    }
    double v = 0.0;
    if (!(in >> v)) throw MappingError(path + ": truncated PLY data");
    return v;
  }
};

// Property indices of x, y, z, red, green, blue in an element (-1 when absent).
using FieldIndices = std::array<int, 6>;

FieldIndices fieldIndices(const PlyElement& e) {
  FieldIndices idx = {-1, -1, -1, -1, -1, -1};
  for (std::size_t k = 0; k < e.props.size(); ++k) {
    const std::string& n = e.props[k].name;
    const int ki = static_cast<int>(k);
    if (n == "x") idx[0] = ki;
    if (n == "y") idx[1] = ki;
    if (n == "z") idx[2] = ki;
    if (n == "red" || n == "r") idx[3] = ki;
    if (n == "green" || n == "g") idx[4] = ki;
    if (n == "blue" || n == "b") idx[5] = ki;
  }
  return idx;
}

bool hasColours(const FieldIndices& idx) { return idx[3] >= 0 && idx[4] >= 0 && idx[5] >= 0; }

// Binary vertices without list properties: read the whole block, decode by byte offsets.
bool readFixedVertices(std::istream& in, const PlyElement& e, const std::string& path,
                       const FieldIndices& idx, PlyData* data) {
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
  const bool colours = hasColours(idx);
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

// Reads one list property's items into `list`; a length above `available` bytes is corrupt.
void readList(ValueReader& reader, const PlyProperty& p, std::uintmax_t available,
              std::vector<double>* list) {
  const double n = reader.next(p.count_type);
  if (!(n >= 0.0 && n <= static_cast<double>(available))) {
    throw MappingError(reader.path + ": bad PLY list length " + std::to_string(n));
  }
  list->resize(static_cast<std::size_t>(n));
  for (double& v : *list) v = reader.next(p.type);
}

// Fan-triangulates one face's polygon (vertex indices in `list`) into data->triangles.
void addFace(const std::vector<double>& list, const std::string& path, PlyData* data) {
  for (const double v : list) {
    if (!(v >= 0.0 && v < 4294967296.0)) {
      throw MappingError(path + ": bad PLY face index " + std::to_string(v));
    }
  }
  for (std::size_t t = 1; t + 1 < list.size(); ++t) {
    data->triangles.push_back({static_cast<std::uint32_t>(list[0]),
                               static_cast<std::uint32_t>(list[t]),
                               static_cast<std::uint32_t>(list[t + 1])});
  }
}

// Reads element `e` value by value (ASCII, list properties, any non-vertex element): vertices
// (and colours) of a vertex element, triangles of a face element when `is_face`.
void readElementValues(ValueReader& reader, const PlyElement& e, bool is_face,
                       std::uintmax_t available, PlyData* data) {
  const bool is_vertex = e.name == "vertex";
  const FieldIndices idx = fieldIndices(e);
  const bool colours = is_vertex && hasColours(idx);
  std::vector<double> values(e.props.size());
  std::vector<double> list;
  for (std::size_t i = 0; i < e.count; ++i) {
    for (std::size_t k = 0; k < e.props.size(); ++k) {
      const PlyProperty& p = e.props[k];
      if (p.count_type.empty()) {
        values[k] = reader.next(p.type);
        continue;
      }
      readList(reader, p, available, &list);
      if (is_face) addFace(list, reader.path, data);
    }
    if (!is_vertex) continue;
    const auto at = [&values, &idx](int a) { return values[static_cast<std::size_t>(idx[a])]; };
    data->vertices.emplace_back(at(0), at(1), at(2));
    if (colours) data->colors.push_back({toByte(at(3)), toByte(at(4)), toByte(at(5))});
  }
}

void checkFaceIndices(const PlyData& data, const std::string& path) {
  for (const auto& t : data.triangles) {
    if (t[0] >= data.vertices.size() || t[1] >= data.vertices.size() ||
        t[2] >= data.vertices.size()) {
      throw MappingError(path + ": PLY face index out of range (" +
                         std::to_string(data.vertices.size()) + " vertices)");
    }
  }
}

}  // namespace

std::size_t plyScalarSize(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32")
    return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

PlyHeader readPlyHeader(std::istream& in, const std::string& path) {
  std::string line;
  if (!std::getline(in, line) || line.rfind("ply", 0) != 0) {
    throw MappingError(path + ": not a PLY file");
  }
  PlyHeader header;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "format") {
      std::string fmt;
      ls >> fmt;
      if (fmt == "binary_little_endian") {
        header.binary = true;
      } else if (fmt != "ascii") {
        throw MappingError(path + ": unsupported PLY format '" + fmt + "'");
      }
    } else if (word == "element") {
      PlyElement e;
      ls >> e.name >> e.count;
      header.elements.push_back(e);
    } else if (word == "property" && !header.elements.empty()) {
      PlyProperty p;
      std::string t;
      ls >> t;
      if (t == "list") {
        ls >> p.count_type >> p.type >> p.name;
      } else {
        p.type = t;
        ls >> p.name;
      }
      header.elements.back().props.push_back(p);
    } else if (word == "end_header") {
      return header;
    }
  }
  throw MappingError(path + ": PLY header without end_header");
}

PlyData readPly(const std::string& path, bool with_faces) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MappingError(path + ": cannot open PLY file");
  const PlyHeader header = readPlyHeader(in, path);
  const std::vector<PlyElement>& elements = header.elements;
  if (std::count_if(elements.begin(), elements.end(),
                    [](const PlyElement& e) { return e.name == "vertex"; }) > 1) {
    throw MappingError(path + ": PLY file with more than one vertex element");
  }
  PlyData data;
  ValueReader reader{in, path, header.binary};
  for (const PlyElement& e : elements) {
    const bool is_vertex = e.name == "vertex";
    const FieldIndices idx = fieldIndices(e);
    if (is_vertex && (idx[0] < 0 || idx[1] < 0 || idx[2] < 0)) {
      throw MappingError(path + ": PLY vertices without x, y, z");
    }
    if (e.props.empty()) continue;  // no data in the file
    // Every element takes at least one byte: a larger count is a corrupt header.
    const std::uintmax_t available = remainingBytes(in);
    if (e.count > available) {
      throw MappingError(path + ": PLY element '" + e.name + "' count " + std::to_string(e.count) +
                         " exceeds the file size");
    }
    if (is_vertex) data.vertices.reserve(e.count);
    if (header.binary && is_vertex && readFixedVertices(in, e, path, idx, &data)) continue;
    readElementValues(reader, e, e.name == "face" && with_faces, available, &data);
  }
  checkFaceIndices(data, path);
  return data;
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
