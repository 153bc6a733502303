// `vdb_tsdf`: OpenVDB colour TSDF with projective integration and space carving
// (tsdf_volume.hpp). Exports mesh.ply, mesh.obj, tsdf.vdb and its digest tsdf.vdb.crc32. Pose
// updates: the mapping worker rebuilds the volume with the final poses
// (PoseUpdateMode::kReintegrate). A saved map's tsdf.vdb (importMap()) is the volume's start, to
// which each rebuild's reset() returns.
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "dynamap/mapping/backend_params.hpp"
#include "dynamap/mapping/obj_io.hpp"
#include "dynamap/mapping/plugin_api.hpp"
#include "tsdf_volume.hpp"

namespace dynamap {
namespace {

plugin::TsdfOptions readOptions(const BackendParams& params) {
  ParamReader reader("vdb_tsdf", params);
  plugin::TsdfOptions o;
  o.voxel_size_m = reader.getDouble("voxel_size_m", 0.02, 0.002, 1.0);
  o.truncation_m = reader.getDouble("truncation_m", 0.0, 0.0, 10.0);  // 0 = 4 voxels
  if (o.truncation_m <= 0.0) o.truncation_m = 4.0 * o.voxel_size_m;
  if (o.truncation_m < o.voxel_size_m) {
    throw MappingError("mapping.params.vdb_tsdf.truncation_m: must be >= voxel_size_m");
  }
  o.max_weight = static_cast<float>(reader.getDouble("max_weight", 100.0, 1.0, 1e6));
  o.min_weight = static_cast<float>(reader.getDouble("min_weight", 0.0, 0.0, 1e6));
  o.space_carving = reader.getBool("space_carving", true);
  o.linear_weighting =
      reader.getString("weighting", "constant", {"constant", "linear"}) == "linear";
  o.alloc_stride_px = reader.getInt("alloc_stride_px", 4, 1, 64);
  o.carve_stride_px = reader.getInt("carve_stride_px", 12, 1, 256);
  o.free_votes = reader.getBool("free_votes", true);
  o.free_vote_ratio = static_cast<float>(reader.getDouble("free_vote_ratio", 0.5, 0.01, 100.0));
  reader.finish();
  return o;
}

const ObjFormat kObjFormat{"dynamap vdb_tsdf mesh: v x y z r g b (colour in [0, 1])", 5};

class VdbTsdfBackend final : public MapBackend {
 public:
  explicit VdbTsdfBackend(const BackendParams& params) : volume_(readOptions(params)) {}

  void integrate(const KeyframeView& view) override {
    volume_.integrate(*view.camera, *view.static_depth_m,
                      view.bgr != nullptr ? *view.bgr : cv::Mat(), view.T_W_C);
    ++keyframes_;
  }
  void updatePose(std::uint64_t, const Eigen::Isometry3d&) override {}
  PoseUpdateMode poseUpdateMode() const override { return PoseUpdateMode::kReintegrate; }
  bool fusesViews() const override { return true; }
  bool needsPoints() const override { return false; }
  double cellSizeM() const override { return volume_.options().voxel_size_m; }
  void reset() override {
    volume_.reset();
    keyframes_ = 0;
  }
  bool importMap(const std::string& dir) override {
    volume_.importVdb((std::filesystem::path(dir) / "tsdf.vdb").string());
    return true;
  }

  void exportMap(const std::string& dir) override {
    namespace fs = std::filesystem;
    fs::create_directories(dir);
    const openvdb::FloatGrid::ConstPtr voted = volume_.votedTsdf();
    const fs::path d(dir);
    // The grids' file needs no mesh: it is written on a thread of its own while the mesh is made
    // (reading the same grids) and written, the text OBJ on a third.
    const auto on_thread = [](std::exception_ptr& error, auto write) {
      return std::thread([&error, write] {
        try {
          write();
        } catch (...) {
          error = std::current_exception();
        }
      });
    };
    std::exception_ptr vdb_error, obj_error;
    std::thread vdb = on_thread(vdb_error, [&] {
      const std::string vdb_path = (d / "tsdf.vdb").string();
      writeAtomically(vdb_path, [&](const std::string& tmp) { volume_.writeVdb(tmp, voted); });
      writeAtomically(vdb_path + plugin::kDigestSuffix, [&](const std::string& tmp) {
        std::ofstream(tmp) << plugin::fileDigest(vdb_path) << "\n";
      });
    });
    PlyData mesh;  // outlives every thread that reads it, also when a write throws
    std::thread obj;
    try {
      mesh = volume_.extractMesh(*voted);
      obj = on_thread(obj_error, [&] {
        writeAtomically((d / "mesh.obj").string(),
                        [&](const std::string& tmp) { writeObj(tmp, mesh, kObjFormat); });
      });
      writeAtomically((d / "mesh.ply").string(),
                      [&](const std::string& tmp) { writePly(tmp, mesh); });
      obj.join();
    } catch (...) {
      if (obj.joinable()) obj.join();
      vdb.join();
      throw;
    }
    vdb.join();
    if (obj_error) std::rethrow_exception(obj_error);
    if (vdb_error) std::rethrow_exception(vdb_error);
  }

  MapStats stats() const override {
    MapStats s;
    s.keyframes = keyframes_;
    s.elements = volume_.activeVoxels();
    s.memory_bytes = volume_.memoryBytes();
    s.element_kind = "voxels";
    return s;
  }

 private:
  plugin::TsdfVolume volume_;
  std::size_t keyframes_ = 0;
};

}  // namespace
}  // namespace dynamap

DYNAMAP_DEFINE_BACKEND(dynamap::VdbTsdfBackend)
