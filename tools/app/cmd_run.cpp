#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "dynamap/system/app_config.hpp"
#include "image_io.hpp"
#include "interrupt.hpp"
#include "output_files.hpp"
#include "pipeline.hpp"
#include "run_options.hpp"
#include "run_outputs.hpp"

namespace dynamap {
namespace {

namespace fs = std::filesystem;

constexpr const char* kDownloadHelp =
    "The TUM RGB-D sequences are public: download e.g. rgbd_dataset_freiburg3_walking_xyz.tgz "
    "from https://cvg.cit.tum.de/data/datasets/rgbd-dataset/download and unpack it; the "
    "Yolo-Fastest detector weights come from https://github.com/dog-qiuqiu/Yolo-Fastest "
    "(ModelZoo/yolo-fastest-1.1_coco). See README.md, section 'Data and models'.";

std::string defaultConfigPath() {
  const fs::path in_source = fs::path(DYNAMAP_SOURCE_DIR) / "config" / "default.yaml";
  return fs::exists(in_source) ? in_source.string() : std::string();
}

int runCommand(const RunOptions& cli) {
  RunOptions options = cli;
  if (options.config_path.empty()) options.config_path = defaultConfigPath();
  if (!fs::is_directory(options.sequence_dir)) {
    std::cerr << "dynamap run: error: sequence folder not found: " << options.sequence_dir << "\n"
              << kDownloadHelp << "\n";
    return 2;
  }
  if (options.realtime) {
    // Real time: the newest frame wins, so the detector and BA must not hold tracking in
    // lockstep (offline runs keep it and repeat exactly). A later --set still wins.
    options.overrides.insert(options.overrides.begin(),
                             {"tracking.ba_lockstep=false", "dynamic.detector_lockstep=false"});
  }
  std::string effective_yaml;
  const AppConfig config = loadAppConfig(options.config_path, options.overrides, &effective_yaml);
  DatasetOptions dataset;
  dataset.max_time_diff_s = config.dataset.max_time_diff_s;
  dataset.depth_scale = config.camera.depth_scale;
  dataset.camera = config.resolvedCamera();
  dataset.max_frames = config.dataset.max_frames;
  dataset.keep_unassociated_rgb = config.dataset.keep_unassociated_rgb;
  const TumSequence sequence = TumSequence::open(options.sequence_dir, dataset);

  fs::create_directories(options.out_dir);
  writeTextFileAtomic((fs::path(options.out_dir) / "config.yaml").string(), effective_yaml);

  installInterruptHandler();
  RunResult result;
  std::unique_ptr<Pipeline> pipeline;
  try {
    pipeline = std::make_unique<Pipeline>(options, config, sequence);
  } catch (const std::exception& e) {
    result.status = "failed";
    result.error = e.what();
    writeRunJson(options.out_dir, result);
    throw;
  }
  result = pipeline->run();
  const RunReport report = writeRunOutputs(options, sequence, result, pipeline->timings());
  printRunSummary(std::cout, options, result, report);
  return result.status == "complete" ? 0 : (result.status == "interrupted" ? 130 : 1);
}

}  // namespace

void addRunCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<RunOptions>();
  auto* cmd = app.add_subcommand("run",
                                 "Run SLAM + motion-area removal + dense mapping on a TUM "
                                 "RGB-D sequence folder");
  cmd->add_option("--config", options->config_path, "YAML config (default: config/default.yaml)");
  cmd->add_option("--sequence", options->sequence_dir, "TUM RGB-D sequence folder")->required();
  cmd->add_option("--out", options->out_dir, "output folder")->required();
  cmd->add_option("--set", options->overrides, "override a config key: section.key=value")
      ->take_all();
  cmd->add_option("--poses", options->poses_file,
                  "map with this TUM trajectory instead of tracking (e.g. motion capture)");
  cmd->add_option("--masks", options->masks_dir,
                  "use DIR/<timestamp>.png masks (255 = dynamic) instead of computing them");
  cmd->add_option("--save-map", options->save_map_dir,
                  "write the map (keyframes, landmarks, poses, camera, the backend's map) to DIR "
                  "for a later --load-map");
  cmd->add_option("--load-map", options->load_map_dir,
                  "start in the map a --save-map run wrote to DIR: relocalize in it, report poses "
                  "in its frame, extend it");
  cmd->add_flag("--save-masks", options->save_masks, "write each keyframe's mask to OUT/masks/");
  cmd->add_flag("--debug-images", options->debug_images, "write debug pictures to OUT/debug/");
  cmd->add_flag("--quiet", options->quiet, "no progress line");
  cmd->add_flag("--realtime", options->realtime,
                "frames arrive at their own timestamps; stale work is skipped and counted");
  cmd->callback([options, exit_code] { *exit_code = runCommand(*options); });
}

}  // namespace dynamap
