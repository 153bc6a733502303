// TsdfVolume's file: writeVdb(), fileDigest() for the digest written beside it and, for a saved
// map, readVdb() with every field checked before it is used (a saved volume of another voxel
// size or truncation would fuse wrong values).
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <zlib.h>

#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>

#include "dynamap/mapping/map_backend.hpp"
#include "tsdf_volume.hpp"

namespace dynamap::plugin {
namespace {

/// Errors name the file, the grid and field, and what is wrong.
class VdbReader {
 public:
  explicit VdbReader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void bad(const std::string& field, const std::string& what) const {
    throw MappingError(path_ + ": " + field + ": " + what);
  }

  /// Every grid of the file. The stream throws at the first read that fails: OpenVDB would go
  /// on with what it did not read (a truncated file's string length: gigabytes allocated).
  openvdb::GridPtrVecPtr readAll() const {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path_, ec)) bad("file", "no such file");
    checkDigest();
    try {
      std::ifstream in(path_, std::ios::binary);
      in.exceptions(std::ios::failbit | std::ios::badbit | std::ios::eofbit);
      openvdb::io::Stream stream(in, /*delayLoad=*/false);
      return stream.getGrids();
    } catch (const std::ios_base::failure&) {
      bad("file", "truncated or unreadable (a read went past its end)");
    } catch (const std::exception& e) {
      bad("file", "not a readable OpenVDB file (" + clipped(e.what()) + ")");
    }
  }

  /// The file against the digest beside it, if any.
  void checkDigest() const {
    const std::string digest_path = path_ + kDigestSuffix;
    std::error_code ec;
    if (!std::filesystem::exists(digest_path, ec)) return;
    std::ifstream in(digest_path);
    std::string saved;
    std::getline(in, saved);
    const std::string now = fileDigest(path_);
    if (saved != now) {
      bad("checksum",
          "'" + now + "', " + digest_path + " says '" + clipped(saved) + "' (damaged or replaced)");
    }
  }

  /// The grid `name` as GridT with `background` (null if missing and not `required`).
  template <typename GridT>
  typename GridT::Ptr grid(const openvdb::GridPtrVec& grids, const std::string& name,
                           const typename GridT::ValueType& background, bool required) const {
    const openvdb::GridBase::Ptr base = openvdb::findGridByName(grids, name);
    if (!base) {
      if (required) bad("grid " + name, "missing");
      return nullptr;
    }
    auto typed = openvdb::gridPtrCast<GridT>(base);
    if (!typed) {
      bad("grid " + name, "is a " + base->valueType() + " grid, not " +
                              openvdb::typeNameAsString<typename GridT::ValueType>());
    }
    if (!(typed->background() == background)) bad("grid " + name, "background is not the default");
    return typed;
  }

  void checkTransform(const openvdb::GridBase& grid, double voxel_size_m) const {
    const std::string field = "grid " + grid.getName();
    if (grid.transform().mapType() != openvdb::math::UniformScaleMap::mapType()) {
      bad(field, "transform " + grid.transform().mapType() + " is not a plain voxel scale");
    }
    const double saved = grid.voxelSize()[0];
    if (std::abs(saved - voxel_size_m) > 1e-9 * voxel_size_m) {
      bad(field + ": voxel size", "the map was made with " + number(saved) +
                                      " m, this run's vdb_tsdf.voxel_size_m is " +
                                      number(voxel_size_m));
    }
  }

  void checkTruncation(const openvdb::FloatGrid& tsdf, double truncation_m) const {
    const auto meta = tsdf.getMetadata<openvdb::DoubleMetadata>("truncation_m");
    if (!meta) return;  // written before the field existed
    if (std::abs(meta->value() - truncation_m) > 1e-9 * truncation_m) {
      bad("grid tsdf: truncation_m", "the map was made with " + number(meta->value()) +
                                         " m, this run's vdb_tsdf.truncation_m is " +
                                         number(truncation_m));
    }
  }

  /// Every active value of `grid` passes `ok` (`rule` says what it must be).
  template <typename GridT, typename Ok>
  void checkValues(const GridT& grid, Ok ok, const char* rule) const {
    for (auto it = grid.cbeginValueOn(); it; ++it) {
      if (ok(*it)) continue;
      const openvdb::Coord c = it.getCoord();
      bad("grid " + grid.getName() + ": voxel (" + std::to_string(c.x()) + ", " +
              std::to_string(c.y()) + ", " + std::to_string(c.z()) + ")",
          rule);
    }
  }

 private:
  /// A library's message as one short line (a corrupt file's may hold its garbage).
  static std::string clipped(const std::string& text) {
    std::string out;
    for (const char c : text) {
      const bool space = std::isspace(static_cast<unsigned char>(c)) != 0;
      if (!std::isprint(static_cast<unsigned char>(c)) && !space) continue;
      if (space && (out.empty() || out.back() == ' ')) continue;
      out += space ? ' ' : c;
      if (out.size() >= 120) return out + "...";
    }
    return out;
  }

  static std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.10g", v);
    return buf;
  }

  std::string path_;
};

}  // namespace

std::string fileDigest(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MappingError(path + ": cannot open");
  uLong crc = crc32(0L, Z_NULL, 0);
  std::uintmax_t bytes = 0;
  std::vector<char> buffer(1 << 20);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    crc = crc32(crc, reinterpret_cast<const Bytef*>(buffer.data()), static_cast<uInt>(n));
    bytes += n;
  }
  char text[64];
  std::snprintf(text, sizeof(text), "crc32 %08lx bytes %ju", static_cast<unsigned long>(crc),
                bytes);
  return text;
}

TsdfVolume::Grids TsdfVolume::readVdb(const std::string& path) const {
  const VdbReader reader(path);
  const openvdb::GridPtrVecPtr all = reader.readAll();
  Grids g;
  g.tsdf = reader.grid<openvdb::FloatGrid>(*all, "tsdf", 1.0f, true);
  g.weight = reader.grid<openvdb::FloatGrid>(*all, "weight", 0.0f, true);
  g.color = reader.grid<openvdb::Vec3SGrid>(*all, "color", openvdb::Vec3s(0.0f), true);
  g.free = reader.grid<openvdb::FloatGrid>(*all, "free_views", 0.0f, false);
  if (!g.free || !options_.free_votes) {  // saved without free votes, or this run has none
    g.free = openvdb::FloatGrid::create(0.0f);
    g.free->setTransform(g.tsdf->transform().copy());
    g.free->setName("free_views");
  }
  for (const openvdb::GridBase* grid : {static_cast<const openvdb::GridBase*>(g.tsdf.get()),
                                        static_cast<const openvdb::GridBase*>(g.weight.get()),
                                        static_cast<const openvdb::GridBase*>(g.color.get()),
                                        static_cast<const openvdb::GridBase*>(g.free.get())}) {
    reader.checkTransform(*grid, options_.voxel_size_m);
  }
  reader.checkTruncation(*g.tsdf, options_.truncation_m);
  reader.checkValues(
      *g.tsdf, [](float v) { return v >= -1.0f && v <= 1.0f; }, "not a distance in [-1, 1]");
  reader.checkValues(
      *g.weight, [](float v) { return v >= 0.0f && std::isfinite(v); }, "not a finite weight >= 0");
  reader.checkValues(
      *g.free, [](float v) { return std::isfinite(v); }, "not finite");
  reader.checkValues(
      *g.color, [](const openvdb::Vec3s& c) { return c.isFinite(); }, "colour not finite");
  return g;
}

void TsdfVolume::writeVdb(const std::string& path,
                          const openvdb::FloatGrid::ConstPtr& voted) const {
  openvdb::GridCPtrVec grids{voted, weight_, color_};
  if (options_.free_votes) grids.push_back(free_);
  openvdb::io::File file(path);
  file.write(grids);
  file.close();
}

}  // namespace dynamap::plugin
