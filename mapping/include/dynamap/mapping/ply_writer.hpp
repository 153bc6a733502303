#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace dynamap {

/// Writes a binary little-endian PLY file piece by piece, so that a cloud larger than one copy
/// in memory can be written from where it lies (e.g. keyframe by keyframe): the header with the
/// counts first, then the vertices in as many calls as wanted, then the faces. x y z float32,
/// red green blue uchar when `colours`, faces as a uchar-counted list of int. The file
/// writePly() writes. Not thread-safe; throws MappingError naming the file on any failure, and
/// close() when fewer or more vertices or faces came than the header announced.
class PlyWriter {
 public:
  PlyWriter(const std::string& path, std::size_t vertices, bool colours, std::size_t faces = 0);
  PlyWriter(const PlyWriter&) = delete;
  PlyWriter& operator=(const PlyWriter&) = delete;

  /// `n` vertices; `colors` (RGB, n of them) is read only when the file has colours.
  void addVertices(const Eigen::Vector3f* vertices, const std::array<std::uint8_t, 3>* colors,
                   std::size_t n);
  void addFaces(const std::array<std::uint32_t, 3>* triangles, std::size_t n);
  /// Flushes and checks the counts and the stream.
  void close();

 private:
  void put(const void* bytes, std::size_t n);
  void flushIfFull();
  std::string path_;
  std::ofstream out_;
  bool colours_;
  std::size_t vertices_expected_, faces_expected_;
  std::size_t vertices_ = 0, faces_ = 0;
  std::vector<char> block_;  ///< records packed and written in large blocks
};

}  // namespace dynamap
