#pragma once

#include <string>
#include <vector>

namespace dynamap {

/// What `dynamap run` was asked to do.
struct RunOptions {
  std::string config_path;             ///< empty = config/default.yaml defaults only
  std::vector<std::string> overrides;  ///< "--set section.key=value"
  std::string sequence_dir;
  std::string out_dir;
  std::string poses_file;  ///< map with these TUM poses instead of tracking
  std::string masks_dir;   ///< use DIR/<timestamp>.png masks instead of computing them
  std::string save_map_dir;  ///< write what a later run needs to start in this map
  std::string load_map_dir;  ///< start in the map saved here (System::saveMap())
  bool save_masks = false;
  bool debug_images = false;
  bool quiet = false;
  /// Frames arrive at the sequence's own timestamps (a live camera): when mapping falls
  /// behind, keyframes are dropped (counted); when tracking lags, stale frames are skipped.
  bool realtime = false;
};

}  // namespace dynamap
