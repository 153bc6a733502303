#include "dynamap/mapping/ply_writer.hpp"

#include "dynamap/mapping/map_backend.hpp"
#include "dynamap/mapping/ply_io.hpp"

namespace dynamap {
namespace {
// A write per vertex cost more than the bytes; blocks of this many bytes are written at once.
constexpr std::size_t kBlockBytes = std::size_t{1} << 20;
}  // namespace

PlyWriter::PlyWriter(const std::string& path, std::size_t vertices, bool colours, std::size_t faces)
    : path_(path),
      out_(path, std::ios::binary),
      colours_(colours),
      vertices_expected_(vertices),
      faces_expected_(faces) {
  if (!out_) throw MappingError(path + ": cannot write PLY file");
  out_ << "ply\nformat binary_little_endian 1.0\ncomment dynamap\n"
       << "element vertex " << vertices << "\n"
       << "property float x\nproperty float y\nproperty float z\n";
  if (colours) out_ << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (faces > 0) {
    out_ << "element face " << faces << "\n"
         << "property list uchar int vertex_indices\n";
  }
  out_ << "end_header\n";
  block_.reserve(kBlockBytes + 64);
}

void PlyWriter::put(const void* bytes, std::size_t n) {
  const auto* c = static_cast<const char*>(bytes);
  block_.insert(block_.end(), c, c + n);
}

void PlyWriter::flushIfFull() {
  if (block_.size() < kBlockBytes) return;
  out_.write(block_.data(), static_cast<std::streamsize>(block_.size()));
  block_.clear();
}

void PlyWriter::addVertices(const Eigen::Vector3f* vertices,
                            const std::array<std::uint8_t, 3>* colors, std::size_t n) {
  if (faces_ > 0) throw MappingError(path_ + ": PLY vertices after faces");
  for (std::size_t i = 0; i < n; ++i) {
    put(vertices[i].data(), 3 * sizeof(float));
    if (colours_) put(colors[i].data(), 3);
    flushIfFull();
  }
  vertices_ += n;
}

void PlyWriter::addFaces(const std::array<std::uint32_t, 3>* triangles, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t corners = 3;
    put(&corners, 1);
    const std::int32_t idx[3] = {static_cast<std::int32_t>(triangles[i][0]),
                                 static_cast<std::int32_t>(triangles[i][1]),
                                 static_cast<std::int32_t>(triangles[i][2])};
    put(idx, sizeof(idx));
    flushIfFull();
  }
  faces_ += n;
}

void PlyWriter::close() {
  out_.write(block_.data(), static_cast<std::streamsize>(block_.size()));
  block_.clear();
  out_.close();
  if (vertices_ != vertices_expected_ || faces_ != faces_expected_) {
    throw MappingError(path_ + ": PLY header announced " + std::to_string(vertices_expected_) +
                       " vertices and " + std::to_string(faces_expected_) + " faces, " +
                       std::to_string(vertices_) + " and " + std::to_string(faces_) + " came");
  }
  if (!out_) throw MappingError(path_ + ": write failed");
}

void writePly(const std::string& path, const PlyData& data) {
  const bool colours = !data.colors.empty() && data.colors.size() == data.vertices.size();
  PlyWriter writer(path, data.vertices.size(), colours, data.triangles.size());
  writer.addVertices(data.vertices.data(), colours ? data.colors.data() : nullptr,
                     data.vertices.size());
  writer.addFaces(data.triangles.data(), data.triangles.size());
  writer.close();
}

}  // namespace dynamap
