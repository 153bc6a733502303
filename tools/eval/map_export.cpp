#include "map_export.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "dynamap/mapping/obj_io.hpp"
#include "dynamap/mapping/ply_io.hpp"

namespace dynamap {
namespace {
namespace fs = std::filesystem;

std::string lowerExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

bool hasColors(const PlyData& map) {
  return !map.colors.empty() && map.colors.size() == map.vertices.size();
}

/// Buffered writer of formatted lines (ASCII formats).
class LineWriter {
 public:
  explicit LineWriter(const std::string& path) : path_(path), out_(path, std::ios::binary) {
    if (!out_) throw MapExportError(path + ": cannot open for writing");
    buffer_.reserve(kFlushBytes + 256);
  }
  template <typename... Args>
  void line(const char* format, Args... args) {
    char text[256];
    const int n = std::snprintf(text, sizeof(text), format, args...);
    buffer_.append(text, static_cast<std::size_t>(std::clamp(n, 0, 255)));
    if (buffer_.size() >= kFlushBytes) flush();
  }
  void text(const std::string& s) { buffer_ += s; }
  void close() {
    flush();
    out_.close();
    if (!out_) throw MapExportError(path_ + ": write failed");
  }

 private:
  static constexpr std::size_t kFlushBytes = 1 << 20;
  void flush() {
    out_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    buffer_.clear();
  }
  std::string path_;
  std::ofstream out_;
  std::string buffer_;
};

void writePcd(const std::string& path, const PlyData& map) {
  const bool rgb = hasColors(map);
  const std::size_t n = map.vertices.size();
  LineWriter out(path);
  out.text("# .PCD v0.7 - Point Cloud Data file format (written by dynamap export)\nVERSION 0.7\n");
  out.text(rgb ? "FIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
               : "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n");
  out.text("WIDTH " + std::to_string(n) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
           std::to_string(n) + "\nDATA ascii\n");
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = map.vertices[i];
    if (rgb) {
      const auto& c = map.colors[i];
      const unsigned packed = (static_cast<unsigned>(c[0]) << 16) |
                              (static_cast<unsigned>(c[1]) << 8) | static_cast<unsigned>(c[2]);
      out.line("%.6f %.6f %.6f %u\n", p.x(), p.y(), p.z(), packed);
    } else {
      out.line("%.6f %.6f %.6f\n", p.x(), p.y(), p.z());
    }
  }
  out.close();
}

void writeXyz(const std::string& path, const PlyData& map) {
  const bool rgb = hasColors(map);
  LineWriter out(path);
  for (std::size_t i = 0; i < map.vertices.size(); ++i) {
    const Eigen::Vector3f& p = map.vertices[i];
    if (rgb) {
      const auto& c = map.colors[i];
      out.line("%.6f %.6f %.6f %u %u %u\n", p.x(), p.y(), p.z(), unsigned{c[0]}, unsigned{c[1]},
               unsigned{c[2]});
    } else {
      out.line("%.6f %.6f %.6f\n", p.x(), p.y(), p.z());
    }
  }
  out.close();
}

}  // namespace

std::string resolveMapFile(const std::string& map) {
  std::error_code ec;
  if (fs::is_regular_file(map, ec)) {
    if (lowerExtension(map) != ".ply") {
      throw MapExportError(map + ": not a .ply file (export reads PLY maps)");
    }
    return map;
  }
  if (!fs::is_directory(map, ec)) throw MapExportError(map + ": no such map file or folder");
  for (const char* name : {"cloud.ply", "mesh.ply"}) {
    const fs::path candidate = fs::path(map) / name;
    if (fs::is_regular_file(candidate, ec)) return candidate.string();
  }
  throw MapExportError(map + ": folder holds neither cloud.ply nor mesh.ply");
}

MapExportResult exportMap(const std::string& map, const std::string& to) {
  const std::string ext = lowerExtension(to);
  if (ext != ".ply" && ext != ".pcd" && ext != ".xyz" && ext != ".obj") {
    throw MapExportError(to + ": unknown export format '" + ext +
                         "' (known: .ply, .pcd, .xyz, .obj)");
  }
  MapExportResult result;
  result.source = resolveMapFile(map);
  if (fs::exists(to) && fs::equivalent(to, result.source)) {
    throw MapExportError(to + ": export target is the source map itself");
  }
  PlyData data;
  try {
    data = readPly(result.source, /*with_faces=*/true);
  } catch (const std::exception& e) {
    throw MapExportError(e.what());  // already names the file
  }
  const bool keeps_faces = ext == ".ply" || ext == ".obj";
  result.points = data.vertices.size();
  result.triangles = keeps_faces ? data.triangles.size() : 0;
  result.dropped_faces = !keeps_faces && !data.triangles.empty();
  try {
    writeAtomically(to, [&](const std::string& tmp) {
      if (ext == ".ply") writePly(tmp, data);
      if (ext == ".pcd") writePcd(tmp, data);
      if (ext == ".xyz") writeXyz(tmp, data);
      if (ext == ".obj") writeObj(tmp, data, ObjFormat{"written by dynamap export", 6});
    });
  } catch (const std::exception& e) {
    const std::string what = e.what();
    throw MapExportError(what.rfind(to, 0) == 0 ? what : to + ": " + what);
  }
  return result;
}

}  // namespace dynamap
