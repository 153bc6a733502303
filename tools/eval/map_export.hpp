#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace dynamap {

/// A map cannot be exported (missing input, unknown format, unwritable output); the message
/// names the file.
class MapExportError : public std::runtime_error {
 public:
  using runtime_error::runtime_error;
};

/// The PLY file of a saved map: `map` itself when it is a .ply file, else map/cloud.ply or
/// map/mesh.ply (in that order). Throws MapExportError naming what was looked for.
std::string resolveMapFile(const std::string& map);

struct MapExportResult {
  std::string source;          ///< the PLY that was read
  std::size_t points = 0;      ///< vertices written
  std::size_t triangles = 0;   ///< faces written (PLY/OBJ only)
  bool dropped_faces = false;  ///< the target format (PCD/XYZ) keeps vertices only
};

/// Converts a saved map (see resolveMapFile) to `to`, whose extension picks the format:
///   .ply  binary little-endian PLY (vertices, colours, faces)
///   .pcd  ASCII PCD v0.7: x y z, plus rgb (packed uint32 0x00RRGGBB) when coloured
///   .xyz  ASCII "x y z" or "x y z r g b" (0-255) per line
///   .obj  Wavefront OBJ: "v x y z [r g b]" (colours 0-1), "f i j k" (1-based)
/// Written atomically. Throws MapExportError naming the file.
MapExportResult exportMap(const std::string& map, const std::string& to);

}  // namespace dynamap
