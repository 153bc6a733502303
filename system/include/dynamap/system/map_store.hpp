#pragma once

#include <stdexcept>
#include <string>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/map_contents.hpp"

namespace dynamap {

/// A saved map that cannot be used: missing, corrupt, truncated, another format version or
/// another camera. The message names the file and the field.
class MapFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Version of the map store's layout; a store of another version is refused by name.
inline constexpr int kMapFormatVersion = 1;
/// The tracker part of a saved map folder: SQLite, tables `meta` (key, value: format_version,
/// camera.fx fy cx cy width height, backend, counts), `landmarks` (id, x y z, descriptor 32
/// bytes, bad, keyframes) and `keyframes` (id, timestamp_s, tx ty tz qx qy qz qw, masked_share,
/// observations: 32 bytes each, landmark id u64, px u v f64, depth_m f64, little-endian).
inline constexpr const char* kMapStoreFile = "map.sqlite";

/// Writes `contents` (ids dense) with the camera and the backend's name into `path` under a
/// temporary name, then renames it. Throws MapFileError.
void writeMapStore(const std::string& path, const MapContents& contents,
                   const PinholeCamera& camera, const std::string& backend);

/// What readMapStore() found besides the contents.
struct MapStoreInfo {
  std::string backend;  ///< the backend the map was made with
};

/// Reads a map store and checks every field: format version, the camera against `camera`
/// (intrinsics and size), dense ids, 32-byte descriptors, finite poses and points, observations
/// of existing landmarks, row counts against `meta`. Throws MapFileError naming `path` and the
/// field; never returns a half-read map.
MapContents readMapStore(const std::string& path, const PinholeCamera& camera,
                         MapStoreInfo* info = nullptr);

}  // namespace dynamap
