#include "ply_colored.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "dynamap/mapping/ply_header.hpp"

namespace dynamap {
namespace {

/// Byte layout of a fixed-size binary vertex record.
struct VertexLayout {
  std::size_t record = 0;
  int xyz[3] = {-1, -1, -1};
  bool xyz_double = false;
  int rgb[3] = {-1, -1, -1};
};

bool vertexLayout(const PlyElement& e, VertexLayout* layout) {
  std::size_t offset = 0;
  int xyz_size[3] = {0, 0, 0};
  const char* xyz_names[3] = {"x", "y", "z"};
  const char* rgb_names[3] = {"red", "green", "blue"};
  for (const PlyProperty& p : e.props) {
    const int size = static_cast<int>(plyScalarSize(p.type));
    if (!p.count_type.empty() || size == 0) return false;
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
  const PlyHeader header = readPlyHeader(in, path);
  VertexLayout layout;
  // Fast path: binary vertices first and no faces (elements after the vertices, such as PCL's
  // "camera", are ignored).
  bool has_faces = false;
  for (const PlyElement& e : header.elements) has_faces |= e.name == "face" && e.count > 0;
  const bool fast = header.binary && !has_faces && !header.elements.empty() &&
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
