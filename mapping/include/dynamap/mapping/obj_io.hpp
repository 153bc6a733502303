#pragma once

#include <string>

#include "dynamap/mapping/ply_io.hpp"

namespace dynamap {

/// What varies between the OBJ files dynamap writes.
struct ObjFormat {
  std::string header;           ///< first line, a comment without its '#' and newline
  int coordinate_decimals = 6;  ///< digits after the point of x y z ("%.<n>f")
};

/// Writes `data` as Wavefront OBJ text: the header comment, one "v x y z" line per vertex
/// (followed by "r g b" in [0, 1] with 4 decimals when every vertex has a colour), then one
/// "f i j k" line per triangle (1-based). Numbers are the characters printf's "%.<n>f" / "%u"
/// would write. Pieces of 64k lines are formatted in parallel (TBB) and written in order, so
/// the bytes do not depend on the thread count. Throws MappingError naming the file.
void writeObj(const std::string& path, const PlyData& data, const ObjFormat& format);

}  // namespace dynamap
