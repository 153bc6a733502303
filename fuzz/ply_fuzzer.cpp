// libFuzzer target: the PLY readers of map files loaded back (mapping ply_io readPly,
// eval readPlyVertices + voxelCentroids, eval readPlyForPreview). The first byte picks the
// reader; the rest is the file. Only std::runtime_error (MappingError) may come out.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "dynamap/mapping/ply_io.hpp"
#include "fuzz_util.hpp"
#include "map_metrics.hpp"
#include "ply_colored.hpp"

namespace {

void checkPly(const dynamap::PlyData& data) {
  if (!data.colors.empty() && data.colors.size() != data.vertices.size()) {
    dynamap::fuzz::fail("colour count differs from vertex count");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::uint8_t mode = data[0];
  const std::string path = dynamap::fuzz::writeScratch(
      "map.ply", std::string(reinterpret_cast<const char*>(data) + 1, size - 1));
  try {
    switch (mode % 4) {
      case 0:
        checkPly(dynamap::readPly(path, /*with_faces=*/false));
        break;
      case 1:
        checkPly(dynamap::readPly(path, /*with_faces=*/true));
        break;
      case 2: {
        const auto points = dynamap::readPlyVertices(path);
        const auto centroids = dynamap::voxelCentroids(points, 0.05);
        if (centroids.size() > points.size()) dynamap::fuzz::fail("more centroids than points");
        break;
      }
      default: {
        std::size_t total = 0;
        const std::size_t max_vertices = mode / 4;  // 0..63, 0 = all
        const dynamap::PlyData preview = dynamap::readPlyForPreview(path, max_vertices, &total);
        checkPly(preview);
        if (preview.vertices.size() > total) dynamap::fuzz::fail("preview has more vertices");
        break;
      }
    }
  } catch (const std::runtime_error&) {
  }
  return 0;
}
