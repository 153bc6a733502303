#include "tum_dataset.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <tuple>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "image_io.hpp"

namespace fs = std::filesystem;

namespace dynamap {
namespace {

std::string where(const std::string& path, int line_number) {
  return path + ":" + std::to_string(line_number) + ": ";
}

/// One image list (rgb.txt or depth.txt): timestamps strictly increasing, absolute paths.
struct ImageList {
  std::vector<double> timestamps_s;
  std::vector<std::string> paths;
};

ImageList readImageList(const fs::path& dir, const std::string& name) {
  const std::string path = (dir / name).string();
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw DatasetError("missing " + name + " in sequence folder " + dir.string() + " (" + path +
                       ")");
  }
  ImageList list;
  int previous_line = 0;
  for (const ListLine& line : readListFile(path)) {
    if (line.fields.size() != 2) {
      throw DatasetError(where(path, line.line_number) + "expected 2 fields 'timestamp filename'" +
                         ", found " + std::to_string(line.fields.size()));
    }
    const double t = parseNumberField(line.fields[0], path, line.line_number, "timestamp");
    if (!list.timestamps_s.empty() && t <= list.timestamps_s.back()) {
      throw DatasetError(where(path, line.line_number) + "timestamp " + line.fields[0] +
                         (t == list.timestamps_s.back() ? " repeats" : " is out of order") +
                         " (previous at line " + std::to_string(previous_line) + ")");
    }
    fs::path image = line.fields[1];
    if (image.is_relative()) image = dir / image;
    list.timestamps_s.push_back(t);
    list.paths.push_back(image.lexically_normal().string());
    previous_line = line.line_number;
  }
  return list;
}

std::string sizeText(const cv::Mat& m) {
  return std::to_string(m.cols) + "x" + std::to_string(m.rows);
}

}  // namespace

std::vector<ListLine> readListFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw DatasetError("cannot open " + path);
  }
  std::vector<ListLine> lines;
  std::string text;
  int line_number = 0;
  while (std::getline(in, text)) {
    ++line_number;
    if (!text.empty() && text[0] == '#') continue;
    std::replace(text.begin(), text.end(), ',', ' ');
    std::replace(text.begin(), text.end(), '\t', ' ');
    std::replace(text.begin(), text.end(), '\r', ' ');
    std::istringstream fields_in(text);
    ListLine line{line_number, {}};
    std::string field;
    while (fields_in >> field) line.fields.push_back(field);
    if (!line.fields.empty()) lines.push_back(std::move(line));
  }
  if (in.bad()) {
    throw DatasetError("error while reading " + path);
  }
  return lines;
}

double parseNumberField(const std::string& field, const std::string& path, int line_number,
                        const char* what) {
  const char* begin = field.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  if (end == begin || *end != '\0' || !std::isfinite(value)) {
    throw DatasetError(where(path, line_number) + what + " '" + field + "' is not a finite number");
  }
  return value;
}

std::vector<std::pair<std::size_t, std::size_t>> associateTimestamps(
    const std::vector<double>& first, const std::vector<double>& second, double max_diff_s) {
  std::vector<std::size_t> second_order(second.size());
  for (std::size_t i = 0; i < second.size(); ++i) second_order[i] = i;
  std::sort(second_order.begin(), second_order.end(),
            [&](std::size_t a, std::size_t b) { return second[a] < second[b]; });
  std::vector<double> second_sorted(second.size());
  for (std::size_t i = 0; i < second.size(); ++i) second_sorted[i] = second[second_order[i]];

  // Candidates (|a - b|, a, b) with |a - b| < max_diff_s, as associate.py builds them.
  std::vector<std::tuple<double, double, double, std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < first.size(); ++i) {
    const double a = first[i];
    auto it = std::lower_bound(second_sorted.begin(), second_sorted.end(), a - max_diff_s);
    for (; it != second_sorted.end() && *it <= a + max_diff_s; ++it) {
      const double diff = std::abs(a - *it);
      if (diff < max_diff_s) {
        const auto k = static_cast<std::size_t>(it - second_sorted.begin());
        candidates.emplace_back(diff, a, *it, i, second_order[k]);
      }
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<char> first_used(first.size(), 0);
  std::vector<char> second_used(second.size(), 0);
  std::vector<std::pair<std::size_t, std::size_t>> matches;
  for (const auto& c : candidates) {
    const std::size_t i = std::get<3>(c);
    const std::size_t j = std::get<4>(c);
    if (first_used[i] || second_used[j]) continue;
    first_used[i] = second_used[j] = 1;
    matches.emplace_back(i, j);
  }
  std::sort(matches.begin(), matches.end(), [&](const auto& x, const auto& y) {
    return std::tie(first[x.first], second[x.second]) < std::tie(first[y.first], second[y.second]);
  });
  return matches;
}

TumSequence TumSequence::open(const std::string& dir, const DatasetOptions& options) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw DatasetError("sequence folder " + dir + " does not exist or is not a folder");
  }
  if (!(options.depth_scale > 0.0)) {
    throw DatasetError("depth_scale must be > 0 (got " + std::to_string(options.depth_scale) + ")");
  }
  const fs::path root = fs::absolute(dir).lexically_normal();
  const ImageList rgb = readImageList(root, "rgb.txt");
  const ImageList depth = readImageList(root, "depth.txt");

  TumSequence seq;
  seq.directory_ = root.string();
  seq.options_ = options;
  std::vector<bool> has_depth(rgb.timestamps_s.size(), false);
  for (const auto& [i, j] :
       associateTimestamps(rgb.timestamps_s, depth.timestamps_s, options.max_time_diff_s)) {
    seq.entries_.push_back(
        {rgb.timestamps_s[i], rgb.paths[i], depth.timestamps_s[j], depth.paths[j]});
    has_depth[i] = true;
  }
  if (options.keep_unassociated_rgb) {
    for (std::size_t i = 0; i < has_depth.size(); ++i) {
      if (!has_depth[i]) seq.entries_.push_back({rgb.timestamps_s[i], rgb.paths[i], 0.0, ""});
    }
    std::sort(seq.entries_.begin(), seq.entries_.end(),
              [](const SequenceEntry& a, const SequenceEntry& b) {
                return a.rgb_timestamp_s < b.rgb_timestamp_s;
              });
  }
  if (options.max_frames > 0 &&
      seq.entries_.size() > static_cast<std::size_t>(options.max_frames)) {
    seq.entries_.resize(static_cast<std::size_t>(options.max_frames));
  }

  const PinholeCamera& cam = options.camera;
  if (cam.hasDistortion()) {
    const cv::Matx33d K(cam.fx, 0.0, cam.cx, 0.0, cam.fy, cam.cy, 0.0, 0.0, 1.0);
    const cv::Mat D(cam.distortion.size(), 1, CV_64F, const_cast<double*>(cam.distortion.data()));
    cv::initUndistortRectifyMap(K, D.clone(), cv::Matx33d::eye(), K,
                                cv::Size(cam.width, cam.height), CV_32FC1, seq.map_x_, seq.map_y_);
  }
  return seq;
}

std::optional<std::string> TumSequence::groundTruthPath() const {
  const fs::path gt = fs::path(directory_) / "groundtruth.txt";
  std::error_code ec;
  if (fs::is_regular_file(gt, ec)) return gt.string();
  return std::nullopt;
}

FrameLoad TumSequence::load(std::size_t index) const {
  FrameLoad result;
  if (index >= entries_.size()) {
    result.error = "frame index " + std::to_string(index) + " out of range (sequence has " +
                   std::to_string(entries_.size()) + " frames)";
    return result;
  }
  const SequenceEntry& entry = entries_[index];
  cv::Mat bgr = readImage(entry.rgb_path, cv::IMREAD_COLOR, &result.error);
  if (bgr.empty()) return result;
  cv::Mat depth_raw = entry.depth_path.empty()
                          ? cv::Mat(cv::Mat::zeros(bgr.size(), CV_16UC1))
                          : readImage(entry.depth_path, cv::IMREAD_UNCHANGED, &result.error);
  if (depth_raw.empty()) return result;
  if (depth_raw.type() != CV_16UC1) {
    result.error = "depth image " + entry.depth_path + " is not 16-bit single-channel (" +
                   std::to_string(depth_raw.channels()) + " channel(s), depth code " +
                   std::to_string(depth_raw.depth()) + ")";
    return result;
  }
  if (depth_raw.size() != bgr.size()) {
    result.error = "depth image " + entry.depth_path + " is " + sizeText(depth_raw) +
                   " but colour image " + entry.rgb_path + " is " + sizeText(bgr);
    return result;
  }
  if (!map_x_.empty()) {
    if (bgr.size() != map_x_.size()) {
      result.error = "colour image " + entry.rgb_path + " is " + sizeText(bgr) +
                     " but the camera is " + sizeText(map_x_) + " (cannot undistort)";
      return result;
    }
    cv::Mat bgr_undistorted;
    cv::Mat depth_undistorted;
    cv::remap(bgr, bgr_undistorted, map_x_, map_y_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    cv::remap(depth_raw, depth_undistorted, map_x_, map_y_, cv::INTER_NEAREST, cv::BORDER_CONSTANT);
    bgr = bgr_undistorted;
    depth_raw = depth_undistorted;
  }
  result.frame.index = index;
  result.frame.timestamp_s = entry.rgb_timestamp_s;
  result.frame.bgr = bgr;
  depth_raw.convertTo(result.frame.depth_m, CV_32F, 1.0 / options_.depth_scale);
  result.ok = true;
  result.error.clear();
  return result;
}

}  // namespace dynamap
