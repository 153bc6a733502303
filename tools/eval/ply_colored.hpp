#pragma once

#include <cstddef>
#include <string>

#include "dynamap/mapping/ply_io.hpp"  // PlyData

namespace dynamap {

/// Vertices, colours and faces of a PLY map for previews, fast on big binary clouds: a point
/// cloud (no faces) with more than `max_vertices` vertices is read with a fixed stride (every
/// k-th vertex), straight from 1 MiB blocks of binary_little_endian data. Meshes are read whole
/// (faces index every vertex). `*total_vertices` (optional) receives the file's vertex count.
/// ASCII and unusual layouts fall back to readPly. Throws std::runtime_error naming the file.
PlyData readPlyForPreview(const std::string& path, std::size_t max_vertices,
                          std::size_t* total_vertices = nullptr);

}  // namespace dynamap
