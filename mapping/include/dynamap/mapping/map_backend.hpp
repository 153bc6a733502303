#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"

namespace dynamap {

/// A mapping problem detected at load/configuration time (unknown backend, bad parameter,
/// unreadable plugin, export failure). The message names the backend, key or file.
class MappingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One keyframe as a backend sees it: plain data, borrowed for the duration of integrate().
/// Mask semantics live only in mapping/ (static_points.cpp): `static_depth_m` already has the
/// dynamic, depth-edge and out-of-range pixels set to 0, and `points_C` / `colors` are the
/// remaining static points in the camera frame (colours are R, G, B).
struct KeyframeView {
  std::uint64_t id = 0;
  double timestamp_s = 0.0;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();  ///< camera -> world
  const PinholeCamera* camera = nullptr;
  const cv::Mat* bgr = nullptr;             ///< CV_8UC3
  const cv::Mat* static_depth_m = nullptr;  ///< CV_32FC1, 0 = not static / no reading
  const std::vector<Eigen::Vector3f>* points_C = nullptr;
  const std::vector<std::array<std::uint8_t, 3>>* colors = nullptr;  ///< RGB, one per point
};

struct MapStats {
  std::size_t keyframes = 0;     ///< keyframes integrated
  std::size_t elements = 0;      ///< points, voxels or occupied cells (see `element_kind`)
  std::size_t memory_bytes = 0;  ///< the backend's own accounting of its map storage
  std::string element_kind;      ///< "points", "voxels", "occupied_cells"
};

/// How a backend follows keyframe pose corrections.
enum class PoseUpdateMode : std::uint8_t {
  kInPlace,      ///< the backend re-transforms its own per-keyframe data in updatePose()
  kReintegrate,  ///< volumetric: the worker rebuilds the map with the final poses (reset())
};

/// A dense-map backend. Implementations live in plugins (plugins/<name>/) and are created by
/// BackendRegistry. Not thread-safe: the mapping worker's thread owns the backend.
class MapBackend {
 public:
  virtual ~MapBackend() = default;
  /// Adds one keyframe's static observation with its current pose.
  virtual void integrate(const KeyframeView& view) = 0;
  /// A corrected pose for an integrated keyframe (unknown ids are ignored).
  virtual void updatePose(std::uint64_t keyframe_id, const Eigen::Isometry3d& T_W_C) = 0;
  virtual PoseUpdateMode poseUpdateMode() const = 0;
  /// Drops every keyframe's content (the worker re-integrates every keyframe after it); a map
  /// taken by importMap() stays.
  virtual void reset() = 0;
  /// Writes the map files into `dir` (created if missing) under stable names, atomically.
  /// Throws MappingError on I/O failure.
  virtual void exportMap(const std::string& dir) = 0;
  virtual MapStats stats() const = 0;
  /// true: each map cell is a vote over the views that saw it (a TSDF's weighted average,
  /// occupancy log-odds), so a few stray pixels of one view are outvoted; false: every observed
  /// point is kept. The worker grows dynamic masks less for a fusing backend.
  virtual bool fusesViews() const { return false; }
  /// false: integrate() reads only `static_depth_m` and `bgr`, and the worker leaves `points_C`
  /// and `colors` empty (a TSDF projects its voxels into the depth image; no points needed).
  virtual bool needsPoints() const { return true; }
  /// Starts from the map that exportMap() wrote into `dir` (world frame), before any keyframe:
  /// that content belongs to no keyframe (no updatePose() moves it, reset() keeps it,
  /// stats().keyframes leaves it out) and keyframes integrate on top of it. Returns false if the
  /// backend cannot take a saved map (nothing changed). A missing, corrupt or mismatched file
  /// (e.g. another voxel size) throws MappingError "<file>: <field>: <what>" and leaves the
  /// backend as it was.
  virtual bool importMap(const std::string& dir) {
    (void)dir;
    return false;
  }
  /// true: deintegrate() takes a keyframe out again, so that the worker moves a kReintegrate
  /// keyframe whose pose changed by taking it out at its old pose and integrating it at the new
  /// one, instead of rebuilding the whole map.
  virtual bool canDeintegrate() const { return false; }
  /// Undoes integrate(view) for the same view (same points, same pose), up to what the backend's
  /// own clamping lost (stats().keyframes counts one less). Only where canDeintegrate().
  virtual void deintegrate(const KeyframeView& view) {
    (void)view;
    throw MappingError("this backend cannot take a keyframe out (canDeintegrate() is false)");
  }
  /// Moves an integrated keyframe from `from` (its pose when it went in) to `to` (same image,
  /// new pose): deintegrate(from) then integrate(to), or what amounts to it where a backend can
  /// do it cheaper (stats().keyframes unchanged). Only where canDeintegrate().
  virtual void moveKeyframe(const KeyframeView& from, const KeyframeView& to) {
    deintegrate(from);
    integrate(to);
  }
  /// The edge of the map's cells (m; 0 = no cells, e.g. points). A kReintegrate keyframe whose
  /// pose moved by less than half a cell stays where it went in (MappingWorker).
  virtual double cellSizeM() const { return 0.0; }
};

/// Backend parameters as given in the configuration (keys without the "<backend>." prefix).
using BackendParams = std::map<std::string, std::string>;

/// The one symbol a plugin exports (see plugin_api.hpp). Returns a new backend owned by the
/// caller; throws MappingError for a bad parameter.
using BackendFactoryFn = MapBackend* (*)(const BackendParams& params);
/// v2: MapBackend::needsPoints(); v3: MapBackend::importMap(); v4: canDeintegrate() and
/// deintegrate(); v5: moveKeyframe(); v6: cellSizeM() (a plugin built for an older version has a
/// shorter vtable: refused by name).
inline constexpr const char* kBackendFactorySymbol = "dynamap_create_backend_v6";

}  // namespace dynamap
