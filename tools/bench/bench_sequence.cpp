#include "bench_sequence.hpp"

#include <filesystem>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "tum_dataset.hpp"

namespace dynamap::bench {

std::optional<Eigen::Isometry3d> interpolatePose(const std::vector<TimedPose>& poses, double t) {
  if (poses.empty() || t < poses.front().timestamp_s || t > poses.back().timestamp_s) {
    return std::nullopt;
  }
  auto it = std::lower_bound(poses.begin(), poses.end(), t,
                             [](const TimedPose& p, double v) { return p.timestamp_s < v; });
  if (it == poses.begin()) return it->T_W_C;
  const TimedPose& b = *it;
  const TimedPose& a = *(it - 1);
  const double s = (t - a.timestamp_s) / (b.timestamp_s - a.timestamp_s);
  const Eigen::Quaterniond qa(a.T_W_C.rotation()), qb(b.T_W_C.rotation());
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = qa.slerp(s, qb).toRotationMatrix();
  T.translation() = (1 - s) * a.T_W_C.translation() + s * b.T_W_C.translation();
  return T;
}

std::vector<BenchFrame> loadBenchFrames(const std::string& dir, int every, int max_frames) {
  namespace fs = std::filesystem;
  const TumSequence seq = TumSequence::open(dir, DatasetOptions{});
  const std::vector<TimedPose> gt = readTrajectory((fs::path(dir) / "groundtruth.txt").string());
  std::vector<BenchFrame> frames;
  const std::size_t step = static_cast<std::size_t>(std::max(1, every));
  for (std::size_t i = 0; i < seq.size(); i += step) {
    const SequenceEntry& e = seq.entries()[i];
    if (e.depth_path.empty()) continue;  // no depth within the association window
    const auto pose = interpolatePose(gt, e.rgb_timestamp_s);
    if (!pose) continue;
    BenchFrame f;
    f.id = i;
    f.timestamp_s = e.rgb_timestamp_s;
    f.rgb_path = e.rgb_path;
    f.depth_path = e.depth_path;
    f.mask_path = (fs::path(dir) / "mask" / fs::path(e.rgb_path).filename())
                      .replace_extension(".png")
                      .string();
    f.T_W_C = *pose;
    frames.push_back(f);
    if (max_frames > 0 && static_cast<int>(frames.size()) >= max_frames) break;
  }
  return frames;
}

LoadedFrame readBenchFrame(const BenchFrame& frame) {
  LoadedFrame out;
  out.bgr = cv::imread(frame.rgb_path, cv::IMREAD_COLOR);
  const cv::Mat raw = cv::imread(frame.depth_path, cv::IMREAD_UNCHANGED);
  if (out.bgr.empty() || raw.empty()) {
    throw std::runtime_error("cannot read " + frame.rgb_path + " / " + frame.depth_path);
  }
  raw.convertTo(out.depth_m, CV_32FC1, 1.0 / 5000.0);
  const cv::Mat mask = cv::imread(frame.mask_path, cv::IMREAD_GRAYSCALE);
  if (mask.empty()) throw std::runtime_error("cannot read " + frame.mask_path);
  out.dynamic_mask = mask;  // 255 = dynamic; 128 (standing person) and 0 are static
  return out;
}

}  // namespace dynamap::bench
