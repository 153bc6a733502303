#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace dynamap {

struct PlyData {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<std::array<std::uint8_t, 3>> colors;  ///< RGB; empty if the file has none
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

/// Reads the vertices (and colours when present) of a PLY file, ASCII or binary_little_endian,
/// tolerating any extra vertex properties; faces are read only when `with_faces`.
/// Throws MappingError naming the file.
PlyData readPly(const std::string& path, bool with_faces = false);

/// Binary little-endian PLY: x y z float32, red green blue uchar (if colours), faces (if any).
/// (PlyWriter in ply_writer.hpp writes the same file piece by piece.)
void writePly(const std::string& path, const PlyData& data);

/// Writes through `write(tmp_path)` to a temporary name in the same folder, then renames it to
/// `final_path`, so readers never see half-written files. Throws MappingError.
void writeAtomically(const std::string& final_path,
                     const std::function<void(const std::string& tmp_path)>& write);

}  // namespace dynamap
