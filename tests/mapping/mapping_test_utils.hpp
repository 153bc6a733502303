#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "dynamap/mapping/backend_registry.hpp"
#include "dynamap/mapping/mapping_worker.hpp"
#include "synthetic_scene.hpp"
#include "test_paths.hpp"

namespace dynamap::test {

inline std::string pluginDir() { return (binaryDir() / "lib").string(); }

/// Test parameters and the "one voxel" tolerance per known backend (others: defaults, 5 cm).
struct BackendCase {
  BackendParams params;
  double voxel_m = 0.05;
};
inline BackendCase backendCase(const std::string& name) {
  static const std::map<std::string, BackendCase> cases = {
      {"points", {{}, 0.01}},
      {"pcl_voxel", {{{"voxel_size_m", "0.02"}}, 0.02}},
      {"vdb_tsdf", {{{"voxel_size_m", "0.02"}}, 0.02}},
      {"octomap", {{{"resolution_m", "0.05"}}, 0.05}},
  };
  const auto it = cases.find(name);
  return it == cases.end() ? BackendCase{} : it->second;
}

/// Keyframe `k` (10 Hz stamps) of a rendered synthetic frame, with its mask if `with_mask`.
inline KeyframePacketPtr syntheticKeyframe(const SyntheticFrame& f, int k, bool with_mask) {
  auto kf = std::make_shared<KeyframePacket>();
  kf->id = static_cast<std::uint64_t>(k);
  kf->timestamp_s = 0.1 * k;
  kf->T_W_C = f.T_W_C;
  kf->bgr = f.bgr;
  kf->depth_m = f.depth_m;
  if (with_mask) kf->dynamic_mask = f.mask;
  return kf;
}

/// Feeds `n` synthetic frames (with masks unless !with_mask) through a MappingWorker, optionally
/// moves every keyframe by `shift` through pose updates, finishes and exports into `dir`.
inline MapStats buildSyntheticMap(std::unique_ptr<MapBackend> backend, int n, bool with_mask,
                                  const Eigen::Vector3d& shift, const std::string& dir,
                                  const StaticPointsOptions& options = {}) {
  const SyntheticScene scene;
  TimingRecorder timings;
  MappingWorker worker(std::move(backend), SyntheticScene::camera(), options, 2, &timings);
  std::vector<PoseUpdate> updates;
  for (int k = 0; k < n; ++k) {
    auto kf = syntheticKeyframe(scene.render(k, n), k, with_mask);
    worker.push(kf);
    updates.push_back({kf->id, Eigen::Translation3d(shift) * kf->T_W_C});
  }
  if (!shift.isZero()) worker.applyPoseUpdates(updates);
  worker.finish();
  worker.exportMap(dir);
  return worker.stats();
}

/// The file every backend can be scored with: mesh.ply if present, else cloud.ply.
inline std::string scoredFile(const std::string& dir) {
  const auto mesh = std::filesystem::path(dir) / "mesh.ply";
  return std::filesystem::exists(mesh) ? mesh.string()
                                       : (std::filesystem::path(dir) / "cloud.ply").string();
}

}  // namespace dynamap::test
