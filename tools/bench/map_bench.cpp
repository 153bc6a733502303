// dynamap_map_bench: feeds a dynamic RGB-D sequence (ground-truth poses and masks) to every
// mapping backend and prints map quality, integration time, memory and export time.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include <CLI/CLI.hpp>

#include "bench_baselines.hpp"
#include "bench_sequence.hpp"
#include "dynamap/core/timing.hpp"
#include "dynamap/mapping/backend_registry.hpp"
#include "dynamap/mapping/mapping_worker.hpp"
#include "map_metrics.hpp"

namespace fs = std::filesystem;
using namespace dynamap;
using namespace dynamap::bench;

namespace {

struct RunSpec {
  std::string label, backend;
  BackendParams params;
  std::string map_file;  // scored file
};
struct RunResult {
  RunSpec spec;
  MapMetrics metrics;
  double static_ms = 0, integrate_ms = 0, integrate_p95_ms = 0, export_ms = 0, total_s = 0;
  std::size_t memory_bytes = 0, rss_growth = 0, elements = 0;
};

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

std::size_t procStatusKb(const char* field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(field, 0) == 0) return std::stoul(line.substr(std::strlen(field) + 1));
  }
  return 0;
}

RunResult runBackend(const BackendRegistry& registry, const RunSpec& spec,
                     const std::vector<BenchFrame>& frames, const PinholeCamera& camera,
                     const StaticPointsOptions& options, const ReferenceClouds& refs,
                     const fs::path& out_dir) {
  RunResult r;
  r.spec = spec;
  const std::size_t rss0 = procStatusKb("VmRSS:");
  const auto t_all = std::chrono::steady_clock::now();
  auto backend = registry.create(spec.backend, spec.params);
  std::vector<double> static_ms, integrate_ms;
  for (const BenchFrame& f : frames) {
    const LoadedFrame lf = readBenchFrame(f);
    auto t0 = std::chrono::steady_clock::now();
    const StaticPoints sp =
        extractStaticPoints(camera, lf.bgr, lf.depth_m, lf.dynamic_mask, options);
    static_ms.push_back(msSince(t0));
    const KeyframeView view = keyframeView(f.id, f.timestamp_s, f.T_W_C, camera, lf.bgr, sp);
    t0 = std::chrono::steady_clock::now();
    backend->integrate(view);
    integrate_ms.push_back(msSince(t0));
  }
  r.rss_growth = (std::max(procStatusKb("VmRSS:"), rss0) - rss0) * 1024;
  const fs::path dir = out_dir / spec.label;
  fs::remove_all(dir);
  const auto t0 = std::chrono::steady_clock::now();
  backend->exportMap(dir.string());
  r.export_ms = msSince(t0);
  r.total_s = msSince(t_all) / 1000.0;
  const MapStats stats = backend->stats();
  r.memory_bytes = stats.memory_bytes;
  r.elements = stats.elements;
  backend.reset();
  r.static_ms = percentile(static_ms, 50);
  r.integrate_ms = percentile(integrate_ms, 50);
  r.integrate_p95_ms = percentile(integrate_ms, 95);
  r.metrics = computeMapMetrics(readPlyVertices((dir / spec.map_file).string()), refs);
  return r;
}

void printRow(const RunResult& r) {
  std::printf(
      "| %-22s | %.4f | %.3f | %.3f | %.3f | %.4f | %7.2f | %7.2f | %7.1f | %7.1f | %8.1f |\n",
      r.spec.label.c_str(), r.metrics.accuracy_mean_m, r.metrics.precision, r.metrics.completeness,
      r.metrics.fscore, r.metrics.ghost_ratio, r.integrate_ms, r.integrate_p95_ms,
      r.memory_bytes / 1048576.0, r.rss_growth / 1048576.0, r.export_ms);
  std::fflush(stdout);
}

// Open3D ScalableTSDFVolume on the same frames (scripts/o3d_tsdf_bench.py); returns its median ms.
double runOpen3d(const std::vector<BenchFrame>& frames, const StaticPointsOptions& o, double voxel,
                 const fs::path& out_dir, const ReferenceClouds& refs, MapMetrics* metrics) {
  const fs::path list = out_dir / "o3d_frames.txt";
  {
    std::ofstream out(list);
    out.precision(10);
    for (const auto& f : frames) {
      out << f.rgb_path << " " << f.depth_path << " " << f.mask_path;
      const Eigen::Matrix4d T = f.T_W_C.matrix();
      for (int i = 0; i < 16; ++i) out << " " << T(i / 4, i % 4);
      out << "\n";
    }
  }
  const fs::path mesh = out_dir / ("o3d_" + std::to_string(int(voxel * 1000)) + "mm.ply");
  std::ostringstream cmd;
  cmd << "OMP_NUM_THREADS=2 OMP_WAIT_POLICY=PASSIVE /usr/bin/python3 " DYNAMAP_SOURCE_DIR
         "/scripts/o3d_tsdf_bench.py "
      << list << " " << voxel << " " << 4 * voxel << " " << o.depth_min_m << " " << o.depth_max_m
      << " " << o.mask_dilation_px << " " << o.depth_edge_threshold_m << " " << mesh;
  FILE* p = popen(cmd.str().c_str(), "r");
  if (p == nullptr) return -1;
  double ms = -1;
  char buf[512];
  while (std::fgets(buf, sizeof(buf), p) != nullptr) {
    std::sscanf(buf, "median_integrate_ms %lf", &ms);
  }
  if (pclose(p) != 0 || ms < 0) return -1;
  *metrics = computeMapMetrics(readPlyVertices(mesh.string()), refs);
  return ms;
}

// README "naive" / "masked" rows: every depth pixel up to 4 m (optionally without the pixels the
// masks mark as people, 255 and 128), 1 cm voxels, to validate the metric implementation.
void validateMetrics(const std::vector<BenchFrame>& frames, const PinholeCamera& camera,
                     const ReferenceClouds& refs) {
  for (const bool masked : {false, true}) {
    std::vector<Eigen::Vector3f> acc;
    StaticPointsOptions o;
    o.depth_min_m = 0.0;
    o.mask_dilation_px = 0;
    o.depth_edge_threshold_m = 0.0;
    for (const BenchFrame& f : frames) {
      LoadedFrame lf = readBenchFrame(f);
      cv::Mat mask = masked ? cv::Mat((lf.dynamic_mask > 0) / 255 * 255) : cv::Mat();
      const StaticPoints sp = extractStaticPoints(camera, lf.bgr, lf.depth_m, mask, o);
      const Eigen::Isometry3f T = f.T_W_C.cast<float>();
      for (const auto& p : sp.points_C) acc.push_back(T * p);
      if (acc.size() > 20000000) acc = voxelCentroids(acc, 0.01);
    }
    const MapMetrics m = computeMapMetrics(acc, refs);
    std::printf(
        "validate %s: accuracy %.3f precision %.3f completeness %.3f ghost %.4f F %.3f "
        "(%zu voxels)\n",
        masked ? "masked" : "naive", m.accuracy_mean_m, m.precision, m.completeness, m.ghost_ratio,
        m.fscore, m.map_points);
  }
}

// Cost of following bundle-adjustment corrections: every `move_every`-th keyframe's pose moved
// by 2 cm through MappingWorker::applyPoseUpdates, then finish() follows the final poses: a
// rebuild of the volume when more than half moved, else each moved keyframe taken out and put
// in again (where the backend can take one out).
void measurePoseFollow(const BackendRegistry& registry, const RunSpec& spec,
                       const std::vector<BenchFrame>& frames, const PinholeCamera& camera,
                       const StaticPointsOptions& options, std::size_t move_every) {
  TimingRecorder timings;
  MappingWorker worker(registry.create(spec.backend, spec.params), camera, options, 4, &timings);
  std::vector<PoseUpdate> updates;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const BenchFrame& f = frames[i];
    const LoadedFrame lf = readBenchFrame(f);
    auto kf = std::make_shared<KeyframePacket>();
    kf->id = f.id;
    kf->timestamp_s = f.timestamp_s;
    kf->T_W_C = f.T_W_C;
    kf->bgr = lf.bgr;
    kf->depth_m = lf.depth_m;
    kf->dynamic_mask = lf.dynamic_mask;
    worker.push(kf);
    if (i % move_every != 0) continue;
    PoseUpdate u{f.id, f.T_W_C};
    u.T_W_C.translation().x() += 0.02;
    updates.push_back(u);
  }
  worker.applyPoseUpdates(updates);
  worker.finish();
  const StageStats rebuild = timings.stats("mapping_rebuild");
  const StageStats move = timings.stats("mapping_move");
  const StageStats one = timings.stats("mapping_move_keyframe");
  if (rebuild.count > 0) {
    std::printf(
        "pose-update rebuild (%s, all %zu keyframes moved 2 cm): %.0f ms at finish() "
        "(%.1f ms per keyframe; worker integrate median %.1f ms incl. static points)\n",
        spec.label.c_str(), worker.reintegratedKeyframes(), rebuild.max_ms,
        rebuild.max_ms / std::max<std::size_t>(1, worker.reintegratedKeyframes()),
        timings.stats("mapping_integrate").median_ms);
  }
  if (move.count > 0) {
    std::printf(
        "pose-update move (%s, %zu of %zu keyframes moved 2 cm): %.0f ms at finish() (per "
        "keyframe median %.1f / p95 %.1f ms; worker integrate median %.1f ms)\n",
        spec.label.c_str(), one.count, frames.size(), move.max_ms, one.median_ms, one.p95_ms,
        timings.stats("mapping_integrate").median_ms);
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"dynamap mapping benchmark"};
  std::string data = std::string(DYNAMAP_SOURCE_DIR) + "/../shared/data/dynamic/teddy_dyn_dev";
  std::string plugin_dir = DYNAMAP_PLUGIN_BUILD_DIR;
  std::string out = "/tmp/dynamap_map_bench";
  int every = 1, max_frames = 0, stride = 2;
  std::vector<std::string> only, sets;
  bool open3d = false, baselines = true, validate = false;
  app.add_option("--data", data, "sequence folder");
  app.add_option("--plugins", plugin_dir, "backend plugin folder");
  app.add_option("--out", out, "output folder for the maps");
  app.add_option("--every", every, "use every k-th frame");
  app.add_option("--max-frames", max_frames, "0 = all");
  app.add_option("--stride", stride, "pixel stride of the static points");
  app.add_option("--only", only, "run only these labels");
  app.add_option("--set", sets, "<label>.<key>=<value>: override a backend parameter of a run");
  app.add_flag("--open3d", open3d, "also run Open3D ScalableTSDFVolume (python3-open3d)");
  app.add_option("--baselines", baselines, "plain OctoMap and one-shot VoxelGrid baselines");
  app.add_flag("--validate", validate, "reproduce the README naive/masked metric rows and exit");
  CLI11_PARSE(app, argc, argv);
  try {
    const PinholeCamera camera = cameraPreset("freiburg3");
    StaticPointsOptions options;
    options.stride = stride;
    const auto frames = loadBenchFrames(data, every, max_frames);
    const ReferenceClouds refs = loadReferenceClouds(data);
    if (validate) {
      validateMetrics(frames, camera, refs);
      return 0;
    }
    const BackendRegistry registry = BackendRegistry::scan({plugin_dir});
    std::printf("frames: %zu, static-point stride %d, plugins:", frames.size(), stride);
    for (const auto& n : registry.names()) std::printf(" %s", n.c_str());
    std::printf("\n");
    std::vector<RunSpec> specs = {
        {"points", "points", {{"keep_every", "2"}}, "cloud.ply"},
        {"pcl_voxel_1cm", "pcl_voxel", {{"voxel_size_m", "0.01"}}, "cloud.ply"},
        {"vdb_tsdf_1cm", "vdb_tsdf", {{"voxel_size_m", "0.01"}}, "mesh.ply"},
        {"vdb_tsdf_2cm", "vdb_tsdf", {{"voxel_size_m", "0.02"}}, "mesh.ply"},
        {"octomap_5cm", "octomap", {{"resolution_m", "0.05"}}, "cloud.ply"},
    };
    std::printf(
        "| run | accuracy (m) | precision | completeness | F-score | ghost | integrate "
        "median ms | p95 ms | map MB (own) | RSS growth MB | export ms |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const auto& set : sets) {
      const auto dot = set.find('.');
      const auto eq = set.find('=');
      if (dot == std::string::npos || eq == std::string::npos || eq < dot) {
        throw std::runtime_error("--set " + set + ": expected <label>.<key>=<value>");
      }
      for (auto& spec : specs) {
        if (spec.label == set.substr(0, dot)) {
          spec.params[set.substr(dot + 1, eq - dot - 1)] = set.substr(eq + 1);
        }
      }
    }
    std::vector<RunResult> results;
    for (const auto& spec : specs) {
      if (!only.empty() && std::find(only.begin(), only.end(), spec.label) == only.end()) continue;
      results.push_back(runBackend(registry, spec, frames, camera, options, refs, fs::path(out)));
      printRow(results.back());
    }
    std::printf(
        "\nstatic-point extraction (mask dilation, edges, back-projection): median %.2f ms\n",
        results.empty() ? 0.0 : results.front().static_ms);
    auto find = [&](const std::string& label) -> const RunResult* {
      for (const auto& r : results)
        if (r.spec.label == label) return &r;
      return nullptr;
    };
    if (baselines && find("octomap_5cm") != nullptr) {
      const auto b = runPlainOctomap(frames, camera, options, 0.05,
                                     (fs::path(out) / "octomap_5cm" / "cloud.ply").string());
      const double fast = find("octomap_5cm")->integrate_ms;
      std::printf(
          "octomap 5 cm: backend %.1f ms/frame vs plain insertPointCloud %.1f ms/frame "
          "(%.1fx faster); occupied cells backend %zu, plain %zu, share of plain cells "
          "also in backend %.3f\n",
          fast, b.median_ms, b.median_ms / fast, b.fast_occupied, b.plain_occupied,
          b.share_of_plain_in_fast);
    }
    if (baselines && find("pcl_voxel_1cm") != nullptr) {
      const auto b = runOneShotVoxelGrid(frames, camera, options, 0.01);
      const RunResult& r = *find("pcl_voxel_1cm");
      std::printf(
          "pcl_voxel 1 cm: incremental %.1f ms/frame (x%zu = %.0f ms total), %zu voxels; "
          "one-shot VoxelGrid over %zu stitched points: stitch %.0f ms + filter %.0f ms, "
          "%zu voxels\n",
          r.integrate_ms, frames.size(), r.integrate_ms * frames.size(), r.elements, b.input_points,
          b.stitch_ms, b.filter_ms, b.output_points);
    }
    if (baselines) {
      for (const auto& spec : specs) {
        if (spec.label == "vdb_tsdf_2cm" || spec.label == "octomap_5cm") {
          measurePoseFollow(registry, spec, frames, camera, options, 1);
          measurePoseFollow(registry, spec, frames, camera, options, 3);
        }
      }
    }
    if (open3d) {
      for (const double voxel : {0.01, 0.02}) {
        MapMetrics m;
        const double ms = runOpen3d(frames, options, voxel, fs::path(out), refs, &m);
        const RunResult* ours = find(voxel < 0.015 ? "vdb_tsdf_1cm" : "vdb_tsdf_2cm");
        if (ms < 0) {
          std::printf("open3d %.0f cm: failed (python3-open3d missing?)\n", voxel * 100);
          continue;
        }
        std::printf(
            "open3d ScalableTSDFVolume %.0f cm: %.2f ms/frame (vdb_tsdf/open3d = %.2f); "
            "precision %.3f completeness %.3f F %.3f ghost %.4f\n",
            voxel * 100, ms, ours ? ours->integrate_ms / ms : 0.0, m.precision, m.completeness,
            m.fscore, m.ghost_ratio);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dynamap_map_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
