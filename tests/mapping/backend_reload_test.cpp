// Reload contract over every backend plugin that takes a saved map (MapBackend::importMap()):
// a map exported and imported into a new backend is what was saved, also after reset() (a
// rebuild); new keyframes extend it, also when their poses move; a missing, corrupt or
// mismatched file is one MappingError naming the file and leaves the backend as it was.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "dynamap/mapping/ply_io.hpp"
#include "mapping_test_utils.hpp"

namespace dynamap::test {
namespace {

namespace fs = std::filesystem;

/// The file each backend imports (the one the corrupt-file test damages).
const std::map<std::string, std::string>& savedFiles() {
  static const std::map<std::string, std::string> files = {{"points", "cloud.ply"},
                                                           {"pcl_voxel", "cloud.ply"},
                                                           {"vdb_tsdf", "tsdf.vdb"},
                                                           {"octomap", "map.ot"}};
  return files;
}

std::vector<std::string> reloadableNames() {
  std::vector<std::string> out;
  for (const auto& name : BackendRegistry::scan({pluginDir()}).names()) {
    if (savedFiles().count(name)) out.push_back(name);
  }
  return out;
}

/// Views of the synthetic room on an orbit around it: run 1 maps orbit steps 0-2, run 2 steps
/// 4-6 (57 degrees on: other walls), so a map of both holds clearly more than either.
constexpr int kOrbitSteps = 3;
const std::vector<int> kRun1 = {0, 1, 2};
const std::vector<int> kRun2 = {4, 5, 6};

struct Outcome {
  MapStats stats;
  std::size_t exported = 0;  ///< vertices of the scored file (mesh or cloud)
  std::size_t reintegrated = 0;
};

std::size_t exportedVertices(const fs::path& dir) {
  return readPly(scoredFile(dir.string())).vertices.size();
}

/// Maps the orbit steps `steps` (masked; once integrated, each pose moved by `shift` through
/// pose updates) on top of the map saved in `import_dir` (none if empty), exports into `dir`.
Outcome mapSteps(std::unique_ptr<MapBackend> backend, const std::vector<int>& steps,
                 const fs::path& import_dir, const fs::path& dir,
                 const Eigen::Vector3d& shift = Eigen::Vector3d::Zero()) {
  const SyntheticScene scene;
  TimingRecorder timings;
  MappingWorker worker(std::move(backend), SyntheticScene::camera(), {}, 2, &timings);
  if (!import_dir.empty()) {
    EXPECT_TRUE(worker.importMap(import_dir.string()));
  }
  std::vector<PoseUpdate> updates;
  for (const int k : steps) {
    auto kf = syntheticKeyframe(scene.render(k, kOrbitSteps), k, true);
    worker.push(kf);
    updates.push_back({kf->id, Eigen::Translation3d(shift) * kf->T_W_C});
  }
  worker.drain();  // integrated with their first poses, as a run's are before its final poses
  if (!shift.isZero()) worker.applyPoseUpdates(updates);
  worker.finish();
  worker.exportMap(dir.string());
  return {worker.stats(), exportedVertices(dir), worker.reintegratedKeyframes()};
}

class BackendReload : public ::testing::TestWithParam<std::string> {
 protected:
  std::unique_ptr<MapBackend> create(const BackendParams& extra = {}) const {
    BackendParams params = backendCase(GetParam()).params;
    for (const auto& kv : extra) params[kv.first] = kv.second;
    return BackendRegistry::scan({pluginDir()}).create(GetParam(), params);
  }
  fs::path savedFile(const fs::path& dir) const { return dir / savedFiles().at(GetParam()); }
};

TEST_P(BackendReload, ImportedMapIsWhatWasSavedAlsoAfterReset) {
  const fs::path saved = freshTempDir("reload_saved_" + GetParam());
  const fs::path again = freshTempDir("reload_again_" + GetParam());
  const Outcome run1 = mapSteps(create(), kRun1, {}, saved);
  ASSERT_GT(run1.exported, 200u);
  auto backend = create();
  ASSERT_TRUE(backend->importMap(saved.string()));
  backend->reset();  // a rebuild's start: the imported map stays
  backend->exportMap(again.string());
  const MapStats stats = backend->stats();
  const std::size_t exported = exportedVertices(again);
  std::printf("%s: saved %zu elements, %zu exported; imported %zu, %zu\n", GetParam().c_str(),
              run1.stats.elements, run1.exported, stats.elements, exported);
  EXPECT_EQ(stats.keyframes, 0u);  // the imported map is no keyframe
  // The same map within 1 % (a point on a voxel face may round into the next voxel).
  EXPECT_NEAR(static_cast<double>(stats.elements), run1.stats.elements, 0.01 * run1.stats.elements);
  EXPECT_NEAR(static_cast<double>(exported), run1.exported, 0.01 * run1.exported);
  // Where it was saved: within one voxel of the static truth (1 % allowed at corners).
  const double tol = backendCase(GetParam()).voxel_m;
  const SyntheticScene scene;
  std::size_t within = 0;
  const auto pts = readPly(scoredFile(again.string())).vertices;
  for (const auto& p : pts) within += scene.staticDistance(p.cast<double>()) <= tol + 1e-3 ? 1 : 0;
  EXPECT_GE(static_cast<double>(within), 0.99 * pts.size());
}

TEST_P(BackendReload, NewKeyframesExtendTheImportedMapAlsoWhenTheirPosesMove) {
  const fs::path saved = freshTempDir("reload_base_" + GetParam());
  const Outcome run1 = mapSteps(create(), kRun1, {}, saved);
  const Outcome only2 = mapSteps(create(), kRun2, {}, freshTempDir("reload_only_" + GetParam()));
  const Outcome both = mapSteps(create(), kRun2, saved, freshTempDir("reload_both_" + GetParam()));
  // Poses moved by 2 cm, and more than half a cell of the backend's map (MapBackend::cellSizeM():
  // a smaller move leaves a keyframe where it went in): a volumetric backend rebuilds from its
  // imported map.
  const double shift_m = std::max(0.02, 0.6 * backendCase(GetParam()).voxel_m);
  const Outcome moved = mapSteps(create(), kRun2, saved, freshTempDir("reload_move_" + GetParam()),
                                 Eigen::Vector3d(shift_m, 0.0, 0.0));
  std::printf(
      "%s elements (exported): run 1 %zu (%zu), run 2 alone %zu (%zu), run 2 on run 1 %zu (%zu), "
      "moved %zu (%zu, %zu re-integrated)\n",
      GetParam().c_str(), run1.stats.elements, run1.exported, only2.stats.elements, only2.exported,
      both.stats.elements, both.exported, moved.stats.elements, moved.exported, moved.reintegrated);
  EXPECT_EQ(both.stats.keyframes, kRun2.size());
  // More than either run alone: run 1's walls and run 2's (each > 10 % more than the larger).
  const auto larger = std::max(run1.stats.elements, only2.stats.elements);
  EXPECT_GT(both.stats.elements, 1.1 * larger);
  EXPECT_GT(both.exported, 1.1 * std::max(run1.exported, only2.exported));
  // A rebuild starts from the imported map: nearly the same map as without the move.
  if (create()->poseUpdateMode() == PoseUpdateMode::kReintegrate) {
    EXPECT_EQ(moved.reintegrated, kRun2.size());
  }
  EXPECT_GT(moved.stats.elements, 1.1 * larger);
  EXPECT_NEAR(static_cast<double>(moved.stats.elements), both.stats.elements,
              0.1 * both.stats.elements);
}

/// Whether importing `dir` into `backend` throws MappingError naming `file` and `field`; the
/// backend keeps `elements`.
void expectImportError(MapBackend& backend, const fs::path& dir, const fs::path& file,
                       const std::string& field, std::size_t elements) {
  try {
    backend.importMap(dir.string());
    ADD_FAILURE() << file << " (" << field << ") was accepted";
  } catch (const MappingError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(file.string() + ": ", 0), 0u) << what;
    EXPECT_NE(what.find(field), std::string::npos) << what;
  }
  EXPECT_EQ(backend.stats().elements, elements);
}

TEST_P(BackendReload, BadFileIsOneErrorNamingItAndKeepsTheMap) {
  const fs::path saved = freshTempDir("reload_good_" + GetParam());
  const fs::path bad = freshTempDir("reload_bad_" + GetParam());
  mapSteps(create(), kRun1, {}, saved);
  auto backend = create();
  ASSERT_TRUE(backend->importMap(saved.string()));
  const std::size_t elements = backend->stats().elements;
  ASSERT_GT(elements, 0u);
  expectImportError(*backend, bad, savedFile(bad), "no such file", elements);
  const auto size = fs::file_size(savedFile(saved));
  fs::copy_file(savedFile(saved), savedFile(bad));
  fs::resize_file(savedFile(bad), size / 2);
  expectImportError(*backend, bad, savedFile(bad), "", elements);  // truncated
  fs::copy_file(savedFile(saved), savedFile(bad), fs::copy_options::overwrite_existing);
  {  // bytes of the middle turned to 0xff
    std::fstream f(savedFile(bad), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(size / 2));
    const std::string junk(std::min<std::uintmax_t>(size / 4, 4096), '\xff');
    f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
  }
  expectImportError(*backend, bad, savedFile(bad), "", elements);
  std::ofstream(savedFile(bad), std::ios::trunc) << "not a map\n";
  expectImportError(*backend, bad, savedFile(bad), "", elements);
}

TEST_P(BackendReload, VolumeOfAnotherVoxelSizeIsRefusedByName) {
  const std::map<std::string, std::pair<std::string, std::string>> other = {
      {"vdb_tsdf", {"voxel_size_m", "0.03"}}, {"octomap", {"resolution_m", "0.1"}}};
  if (!other.count(GetParam())) GTEST_SKIP() << "a point backend's cloud has no voxel size";
  const fs::path saved = freshTempDir("reload_size_" + GetParam());
  mapSteps(create(), kRun1, {}, saved);
  const auto& [key, value] = other.at(GetParam());
  auto backend = create({{key, value}});
  expectImportError(*backend, saved, savedFile(saved), key, 0);
}

// vdb_tsdf writes tsdf.vdb's digest beside it: a damaged byte is refused before OpenVDB parses
// the file (a length in its header taken from garbage is allocated as it says: 4 GB), also where
// the grids would pass every check (a voxel value).
TEST(BackendReloadVdb, DamagedFileIsRefusedByItsDigest) {
  const auto registry = BackendRegistry::scan({pluginDir()});
  if (registry.pluginPath("vdb_tsdf").empty()) GTEST_SKIP() << "vdb_tsdf not built";
  const BackendParams params = backendCase("vdb_tsdf").params;
  const fs::path saved = freshTempDir("reload_digest");
  mapSteps(registry.create("vdb_tsdf", params), kRun1, {}, saved);
  const fs::path file = saved / "tsdf.vdb";
  ASSERT_TRUE(fs::exists(saved / "tsdf.vdb.crc32"));
  const auto size = fs::file_size(file);
  for (const std::uintmax_t at : {std::uintmax_t{140}, size / 2}) {
    const fs::path bad = freshTempDir("reload_digest_bad");
    fs::copy(saved, bad, fs::copy_options::recursive);
    {
      std::fstream f(bad / "tsdf.vdb", std::ios::in | std::ios::out | std::ios::binary);
      f.seekp(static_cast<std::streamoff>(at));
      f.write("\xff\xff\xff\xff", 4);
    }
    auto backend = registry.create("vdb_tsdf", params);
    expectImportError(*backend, bad, bad / "tsdf.vdb", "checksum", 0);
  }
}

INSTANTIATE_TEST_SUITE_P(AllBackends, BackendReload, ::testing::ValuesIn(reloadableNames()),
                         [](const auto& info) { return info.param; });
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(BackendReload);

// A backend that cannot take a saved map (the default importMap(), as a third party's plugin
// built without it) says so and changes nothing.
TEST(BackendReloadDefault, BackendWithoutImportDeclines) {
  class NoImport final : public MapBackend {
   public:
    void integrate(const KeyframeView&) override {}
    void updatePose(std::uint64_t, const Eigen::Isometry3d&) override {}
    PoseUpdateMode poseUpdateMode() const override { return PoseUpdateMode::kInPlace; }
    void reset() override {}
    void exportMap(const std::string&) override {}
    MapStats stats() const override { return {}; }
  };
  TimingRecorder timings;
  MappingWorker worker(std::make_unique<NoImport>(), SyntheticScene::camera(), {}, 2, &timings);
  EXPECT_FALSE(worker.importMap(freshTempDir("reload_declined").string()));
}

}  // namespace
}  // namespace dynamap::test
