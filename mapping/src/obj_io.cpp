#include "dynamap/mapping/obj_io.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <vector>

#include <tbb/parallel_for.h>

#include "dynamap/mapping/map_backend.hpp"  // MappingError

namespace dynamap {
namespace {

/// Appends `value` as printf's "%.<precision>f" writes it (std::to_chars promises the same
/// characters, without printf's format parsing: ~4 x faster).
void appendFixed(std::string& out, double value, int precision) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), value, std::chars_format::fixed, precision);
  if (r.ec == std::errc()) {
    out.append(buf, r.ptr);
  } else {  // |value| of 1e50 and more: not a map coordinate, but written as printf would
    char big[400];
    std::snprintf(big, sizeof(big), "%.*f", precision, value);
    out += big;
  }
}

void appendIndex(std::string& out, std::uint32_t index) {
  char buf[16];
  const auto r = std::to_chars(buf, buf + sizeof(buf), index);
  out.append(buf, r.ptr);
}

/// The OBJ text of vertices [begin, end) or, with `faces`, of triangles [begin, end).
std::string objLines(const PlyData& data, const ObjFormat& format, bool faces, std::size_t begin,
                     std::size_t end) {
  const bool colors = data.colors.size() == data.vertices.size() && !data.colors.empty();
  std::string text;
  text.reserve((end - begin) * (faces ? 24 : 56));
  for (std::size_t i = begin; i < end; ++i) {
    if (faces) {
      text += 'f';
      for (const std::uint32_t index : data.triangles[i]) {
        text += ' ';
        appendIndex(text, index + 1);
      }
    } else {
      const auto& p = data.vertices[i];
      text += 'v';
      for (int a = 0; a < 3; ++a) {
        text += ' ';
        appendFixed(text, p[a], format.coordinate_decimals);
      }
      for (int a = 0; colors && a < 3; ++a) {
        text += ' ';
        appendFixed(text, data.colors[i][static_cast<std::size_t>(a)] / 255.0, 4);
      }
    }
    text += '\n';
  }
  return text;
}

}  // namespace

void writeObj(const std::string& path, const PlyData& data, const ObjFormat& format) {
  constexpr std::size_t kLines = 1 << 16;
  const std::size_t nv = data.vertices.size(), nf = data.triangles.size();
  const std::size_t vertex_pieces = (nv + kLines - 1) / kLines;
  std::vector<std::string> pieces(vertex_pieces + (nf + kLines - 1) / kLines);
  tbb::parallel_for(std::size_t{0}, pieces.size(), [&](std::size_t k) {
    const bool faces = k >= vertex_pieces;
    const std::size_t begin = (faces ? k - vertex_pieces : k) * kLines;
    pieces[k] = objLines(data, format, faces, begin, std::min(faces ? nf : nv, begin + kLines));
  });
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) throw MappingError(path + ": cannot open for writing");
  const std::string header = "# " + format.header + "\n";
  bool ok = std::fwrite(header.data(), 1, header.size(), f) == header.size();
  for (const std::string& piece : pieces) {
    ok = ok && std::fwrite(piece.data(), 1, piece.size(), f) == piece.size();
  }
  ok = ok && std::ferror(f) == 0;
  if (std::fclose(f) != 0 || !ok) throw MappingError(path + ": write failed");
}

}  // namespace dynamap
