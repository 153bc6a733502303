#pragma once
// The PLY header as the map readers see it: mapping's readPly and the preview reader of
// tools/eval (ply_colored.cpp) parse it with this one function.

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

namespace dynamap {

/// One property of a PLY element: a scalar, or a list when `count_type` is non-empty (`type` is
/// then the item type).
struct PlyProperty {
  std::string name;
  std::string type;
  std::string count_type;
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> props;
};

struct PlyHeader {
  bool binary = false;  ///< binary_little_endian (else ascii)
  std::vector<PlyElement> elements;
};

/// Reads a PLY header up to and including its end_header line, leaving `in` at the first data
/// byte. Throws MappingError naming `path` for a file that is not PLY, a format other than ascii
/// or binary_little_endian, or a header without end_header. Thread-safe (no shared state).
PlyHeader readPlyHeader(std::istream& in, const std::string& path);

/// Bytes of one value of PLY scalar type `type` ("float", "uchar", "int32", ...); 0 if unknown.
std::size_t plyScalarSize(const std::string& type);

}  // namespace dynamap
