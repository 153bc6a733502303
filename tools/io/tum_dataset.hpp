#pragma once

#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/frame.hpp"

namespace dynamap {

/// Load-time error of a dataset or trajectory file; the message names the file (and line).
class DatasetError : public std::runtime_error {
 public:
  using runtime_error::runtime_error;
};

struct DatasetOptions {
  double max_time_diff_s = 0.02;  ///< colour/depth association window (strict <)
  double depth_scale = 5000.0;    ///< depth PNG units per metre
  PinholeCamera camera;           ///< distortion != 0 -> frames are undistorted on load
  int max_frames = 0;             ///< 0 = all associated frames
  /// Keep colour frames that found no depth within the window (TUM sequences have a few):
  /// they load with an all-zero depth image; the tracker poses them without changing its state,
  /// so every other pose is the same as when they are skipped.
  bool keep_unassociated_rgb = true;
};

/// One associated colour + depth pair. Paths are absolute. `depth_path` is empty for a colour
/// frame kept without depth (DatasetOptions::keep_unassociated_rgb).
struct SequenceEntry {
  double rgb_timestamp_s;
  std::string rgb_path;
  double depth_timestamp_s;
  std::string depth_path;
};

/// Outcome of reading one frame. ok == false is a "bad frame" (missing, corrupt or
/// wrong-size image): `error` says why and the run goes on.
struct FrameLoad {
  bool ok = false;
  std::string error;
  RgbdFrame frame;
};

/// A TUM RGB-D sequence folder (rgb.txt, depth.txt, optional groundtruth.txt).
class TumSequence {
 public:
  /// Reads and associates rgb.txt / depth.txt. Throws DatasetError naming file:line.
  static TumSequence open(const std::string& dir, const DatasetOptions& options);

  std::size_t size() const { return entries_.size(); }
  const std::vector<SequenceEntry>& entries() const { return entries_; }
  /// dir/groundtruth.txt when it exists.
  std::optional<std::string> groundTruthPath() const;
  const std::string& directory() const { return directory_; }

  /// Reads colour (BGR) and depth (metres, CV_32FC1, 0 = no reading) of entry `index`,
  /// undistorted when the camera has distortion. Thread-safe (const, no shared mutation).
  FrameLoad load(std::size_t index) const;

 private:
  std::string directory_;
  DatasetOptions options_;
  std::vector<SequenceEntry> entries_;
  // Undistortion maps, computed once in open() (empty when the camera has no distortion).
  cv::Mat map_x_;
  cv::Mat map_y_;
};

/// One non-comment line of a whitespace/comma/tab separated list file.
struct ListLine {
  int line_number;  ///< 1-based line in the file
  std::vector<std::string> fields;
};

/// Reads a TUM-style list file: '#' lines and blank lines skipped, ',' and '\t' count as
/// spaces. Throws DatasetError "cannot open <path>" when the file cannot be read.
std::vector<ListLine> readListFile(const std::string& path);

/// Parses a number field; throws DatasetError "file:line: ..." when it is not a finite number.
double parseNumberField(const std::string& field, const std::string& path, int line_number,
                        const char* what);

/// TUM associate.py: candidate pairs |first - second| < max_diff_s, taken greedily by
/// increasing difference (ties by first, then second stamp), each stamp used once.
/// Returns (index into first, index into second), sorted by first stamp.
std::vector<std::pair<std::size_t, std::size_t>> associateTimestamps(
    const std::vector<double>& first, const std::vector<double>& second, double max_diff_s);

}  // namespace dynamap
