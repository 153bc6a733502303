#include "ply_colored.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace dynamap {
namespace {

struct Prop {
  std::string name, type, count_type;  // count_type non-empty for lists
};
struct Elem {
  std::string name;
  std::size_t count = 0;
  std::vector<Prop> props;
};
struct Header {
  bool binary_le = false;
  std::vector<Elem> elements;
};

Header readHeader(std::istream& in, const std::string& path) {
  std::string line;
  if (!std::getline(in, line) || line.rfind("ply", 0) != 0) {
    throw std::runtime_error(path + ": not a PLY file");
  }
  Header h;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "format") {
      std::string fmt;
      ls >> fmt;
      h.binary_le = fmt == "binary_little_endian";
    } else if (word == "element") {
      Elem e;
      ls >> e.name >> e.count;
      h.elements.push_back(e);
    } else if (word == "property" && !h.elements.empty()) {
      Prop p;
      ls >> p.type;
      if (p.type == "list") ls >> p.count_type >> p.type;
      ls >> p.name;
      h.elements.back().props.push_back(p);
    } else if (word == "end_header") {
      return h;
    }
  }
  throw std::runtime_error(path + ": PLY header without end_header");
}

int scalarSize(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32")
    return 4;
  if (t == "double" || t == "float64") return 8;
  return -1;
}

/// Byte layout of a fixed-size binary vertex record.
struct VertexLayout {
  std::size_t record = 0;
  int xyz[3] = {-1, -1, -1};
  bool xyz_double = false;
  int rgb[3] = {-1, -1, -1};
};

bool vertexLayout(const Elem& e, VertexLayout* layout) {
  std::size_t offset = 0;
  int xyz_size[3] = {0, 0, 0};
  const char* xyz_names[3] = {"x", "y", "z"};
  const char* rgb_names[3] = {"red", "green", "blue"};
  for (const Prop& p : e.props) {
    const int size = scalarSize(p.type);
    if (!p.count_type.empty() || size < 0) return false;
    for (int k = 0; k < 3; ++k) {
      if (p.name == xyz_names[k]) {
        if (p.type != "float" && p.type != "float32" && p.type != "double" && p.type != "float64")
          return false;
        layout->xyz[k] = static_cast<int>(offset);
        layout->xyz_double = size == 8;
        xyz_size[k] = size;
      }
      if (p.name == rgb_names[k] && size == 1) layout->rgb[k] = static_cast<int>(offset);
    }
    offset += static_cast<std::size_t>(size);
  }
  layout->record = offset;
  // Mixed float/double coordinates: the general reader.
  if (xyz_size[0] != xyz_size[1] || xyz_size[1] != xyz_size[2]) return false;
  return layout->xyz[0] >= 0 && layout->xyz[1] >= 0 && layout->xyz[2] >= 0;
}

float readCoord(const char* p, bool is_double) {
  if (is_double) {
    double d;
    std::memcpy(&d, p, sizeof(d));
    return static_cast<float>(d);
  }
  float f;
  std::memcpy(&f, p, sizeof(f));
  return f;
}

PlyData subsample(PlyData data, std::size_t max_vertices) {
  if (!data.triangles.empty() || data.vertices.size() <= max_vertices || max_vertices == 0) {
    return data;
  }
  const std::size_t stride = (data.vertices.size() + max_vertices - 1) / max_vertices;
  const bool colours = data.colors.size() == data.vertices.size();
  PlyData out;
  for (std::size_t i = 0; i < data.vertices.size(); i += stride) {
    out.vertices.push_back(data.vertices[i]);
    if (colours) out.colors.push_back(data.colors[i]);
  }
  return out;
}

}  // namespace

PlyData readPlyForPreview(const std::string& path, std::size_t max_vertices,
                          std::size_t* total_vertices) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open PLY file");
  const Header header = readHeader(in, path);
  VertexLayout layout;
  // Fast path: binary vertices first and no faces (elements after the vertices, such as PCL's
  // "camera", are ignored).
  bool has_faces = false;
  for (const Elem& e : header.elements) has_faces |= e.name == "face" && e.count > 0;
  const bool fast = header.binary_le && !has_faces && !header.elements.empty() &&
                    header.elements[0].name == "vertex" &&
                    vertexLayout(header.elements[0], &layout);
  if (!fast) {  // meshes, ASCII, unusual layouts: the general reader
    PlyData data = readPly(path, /*with_faces=*/true);
    if (total_vertices) *total_vertices = data.vertices.size();
    return subsample(std::move(data), max_vertices);
  }
  const std::size_t count = header.elements[0].count;
  const std::streampos data_begin = in.tellg();
  in.seekg(0, std::ios::end);
  const std::streamoff data_bytes = in.tellg() - data_begin;
  in.seekg(data_begin);
  if (data_begin < 0 || data_bytes < 0 ||
      count > static_cast<std::size_t>(data_bytes) / layout.record) {
    throw std::runtime_error(path + ": truncated PLY data (" + std::to_string(count) +
                             " vertices announced)");
  }
  if (total_vertices) *total_vertices = count;
  const std::size_t stride =
      max_vertices > 0 && count > max_vertices ? (count + max_vertices - 1) / max_vertices : 1;
  const bool colours = layout.rgb[0] >= 0 && layout.rgb[1] >= 0 && layout.rgb[2] >= 0;
  PlyData data;
  data.vertices.reserve(count / stride + 1);
  if (colours) data.colors.reserve(count / stride + 1);
  const std::size_t per_block = std::max<std::size_t>(1, (1u << 20) / layout.record);
  std::vector<char> block(per_block * layout.record);
  for (std::size_t first = 0; first < count; first += per_block) {
    const std::size_t n = std::min(per_block, count - first);
    if (!in.read(block.data(), static_cast<std::streamsize>(n * layout.record))) {
      throw std::runtime_error(path + ": truncated PLY data");
    }
    std::size_t i = (stride - first % stride) % stride;  // first multiple of stride in block
    for (; i < n; i += stride) {
      const char* r = block.data() + i * layout.record;
      data.vertices.emplace_back(readCoord(r + layout.xyz[0], layout.xyz_double),
                                 readCoord(r + layout.xyz[1], layout.xyz_double),
                                 readCoord(r + layout.xyz[2], layout.xyz_double));
      if (colours) {
        data.colors.push_back({static_cast<std::uint8_t>(r[layout.rgb[0]]),
                               static_cast<std::uint8_t>(r[layout.rgb[1]]),
                               static_cast<std::uint8_t>(r[layout.rgb[2]])});
      }
    }
  }
  return data;
}

}  // namespace dynamap
