#pragma once
// Evaluation harness for motion-area removal on teddy_dyn_dev without the tracker: loads
// frames, builds LK matches between consecutive frames, scores masks against ground truth.
// Header-only; shared by tools/bench_dynamic/dyn_bench.cpp and tests/dynamic.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "dynamap/core/frame.hpp"
#include "dynamap/core/motion_filter.hpp"
#include "mask_eval.hpp"
#include "trajectory_io.hpp"
#include "tum_dataset.hpp"

namespace dynamap::dynbench {

/// A TUM image list (rgb.txt, depth.txt, mask.txt) read by tools/io's readListFile.
struct StampedFiles {
  std::vector<double> stamps;
  std::vector<std::string> files;  ///< relative to the sequence folder
};

inline StampedFiles readStampedFiles(const std::filesystem::path& path) {
  StampedFiles out;
  for (const ListLine& line : readListFile(path.string())) {
    if (line.fields.size() < 2) continue;
    out.stamps.push_back(
        parseNumberField(line.fields[0], path.string(), line.line_number, "timestamp"));
    out.files.push_back(line.fields[1]);
  }
  return out;
}

/// Index of the stamp in `stamps` nearest to `stamp` (the first of equally near ones).
inline std::size_t nearestIndex(const std::vector<double>& stamps, double stamp) {
  const auto closer = [&](double a, double b) { return std::abs(a - stamp) < std::abs(b - stamp); };
  return static_cast<std::size_t>(std::min_element(stamps.begin(), stamps.end(), closer) -
                                  stamps.begin());
}

struct SequenceFrame {
  RgbdFrame frame;
  cv::Mat gray;
  cv::Mat gt_mask;     ///< 255 moving person, 128 standing person
  cv::Mat teddy_mask;  ///< 255 = teddy (and the top of its box)
};

/// teddy_dyn_dev: rgb/depth/mask lists (depth and mask associated by nearest stamp, with no
/// window: 7 colour images have no depth within 0.02 s), the ground-truth poses (readTrajectory),
/// and the teddy as a world-frame ball (centre measured from frame 0: median of the near pixels
/// on the teddy back-projected with the ground-truth pose).
class DynSequence {
 public:
  explicit DynSequence(const std::filesystem::path& dir)
      : dir_(dir),
        rgb_(readStampedFiles(dir / "rgb.txt")),
        depth_(readStampedFiles(dir / "depth.txt")),
        mask_(readStampedFiles(dir / "mask.txt")),
        poses_(readTrajectory((dir / "groundtruth.txt").string())) {
    for (const TimedPose& p : poses_) pose_stamps_.push_back(p.timestamp_s);
  }
  std::size_t size() const { return rgb_.stamps.size(); }

  SequenceFrame load(std::size_t i) const {
    SequenceFrame f;
    const double stamp = rgb_.stamps[i];
    f.frame.index = i;
    f.frame.timestamp_s = stamp;
    f.frame.bgr = cv::imread((dir_ / rgb_.files[i]).string(), cv::IMREAD_COLOR);
    const std::string& depth_file = depth_.files[nearestIndex(depth_.stamps, stamp)];
    const cv::Mat d16 = cv::imread((dir_ / depth_file).string(), cv::IMREAD_UNCHANGED);
    d16.convertTo(f.frame.depth_m, CV_32F, 1.0 / 5000.0);
    const std::string& mask_file = mask_.files[nearestIndex(mask_.stamps, stamp)];
    f.gt_mask = cv::imread((dir_ / mask_file).string(), cv::IMREAD_GRAYSCALE);
    if (f.frame.bgr.empty() || d16.empty() || f.gt_mask.empty()) {
      throw std::runtime_error("cannot read frame " + std::to_string(i) + " of " + dir_.string());
    }
    cv::cvtColor(f.frame.bgr, f.gray, cv::COLOR_BGR2GRAY);
    f.teddy_mask = teddyMask(f.frame.depth_m, stamp, f.gt_mask);
    return f;
  }

  /// Ground-truth camera-to-world pose nearest to `stamp` (false if none within 0.02 s).
  bool gtPose(double stamp, Eigen::Isometry3d* T_W_C) const {
    if (poses_.empty()) return false;
    const TimedPose& p = poses_[nearestIndex(pose_stamps_, stamp)];
    if (std::abs(p.timestamp_s - stamp) > 0.02) return false;
    *T_W_C = p.T_W_C;
    return true;
  }

 private:
  cv::Mat teddyMask(const cv::Mat& depth, double stamp, const cv::Mat& gt) const {
    const Eigen::Isometry3d& T_W_C = poses_[nearestIndex(pose_stamps_, stamp)].T_W_C;
    const Eigen::Matrix3d R = T_W_C.linear();
    const Eigen::Vector3d t = T_W_C.translation(), centre(-1.7037, 0.0019, 1.2005);
    cv::Mat out = cv::Mat::zeros(depth.size(), CV_8UC1);
    for (int v = 0; v < depth.rows; ++v) {
      for (int u = 0; u < depth.cols; ++u) {
        const double z = depth.at<float>(v, u);
        if (z <= 0.0 || gt.at<uchar>(v, u) != 0) continue;
        const Eigen::Vector3d p_C((u - 320.1) * z / 535.4, (v - 247.6) * z / 539.2, z);
        if ((R * p_C + t - centre).norm() < 0.45) out.at<uchar>(v, u) = 255;
      }
    }
    return out;
  }

  std::filesystem::path dir_;
  StampedFiles rgb_, depth_, mask_;
  std::vector<TimedPose> poses_;
  std::vector<double> pose_stamps_;
};

/// Good features in the previous frame tracked by pyramidal LK (6 levels) with a
/// forward-backward check (< 1 px).
inline FeatureMatches trackLk(const cv::Mat& prev_gray, const cv::Mat& cur_gray,
                              int max_corners = 1000) {
  FeatureMatches m;
  std::vector<cv::Point2f> p0, p1, back;
  cv::goodFeaturesToTrack(prev_gray, p0, max_corners, 0.01, 8);
  if (p0.empty()) return m;
  std::vector<uchar> st, st_back;
  std::vector<float> err;
  const cv::Size win(21, 21);
  cv::calcOpticalFlowPyrLK(prev_gray, cur_gray, p0, p1, st, err, win, 5);
  cv::calcOpticalFlowPyrLK(cur_gray, prev_gray, p1, back, st_back, err, win, 5);
  const cv::Rect image(0, 0, cur_gray.cols, cur_gray.rows);
  for (std::size_t i = 0; i < p0.size(); ++i) {
    if (!st[i] || !st_back[i] || cv::norm(back[i] - p0[i]) > 1.0 || !image.contains(p1[i]))
      continue;
    m.prev_px.push_back(p0[i]);
    m.cur_px.push_back(p1[i]);
  }
  return m;
}

struct MaskScore {
  bool moving_visible = false;   ///< the GT has moving-person pixels
  double iou = 0.0;              ///< IoU of mask with GT==255
  double standing_masked = 0.0;  ///< share of GT==128 pixels masked (-1 if none visible)
  double teddy_masked = 0.0;     ///< share of teddy pixels masked (-1 if none visible)
  double masked_share = 0.0;     ///< share of the image masked
  long standing_px = 0, standing_masked_px = 0, teddy_px = 0, teddy_masked_px = 0;
};

/// tools/eval's scoreMask (any non-zero pixel of `mask_in` counts as masked) plus the teddy.
inline MaskScore scoreMask(const cv::Mat& mask_in, const cv::Mat& gt, const cv::Mat& teddy) {
  const cv::Mat mask = mask_in.empty() ? cv::Mat::zeros(gt.size(), CV_8UC1) : (mask_in > 0);
  const MaskFrameScore f = dynamap::scoreMask(mask, gt);
  MaskScore s;
  s.moving_visible = f.gt_moving > 0;
  s.iou = f.gt_moving + f.est_dynamic > 0 ? f.iou() : 0.0;
  s.standing_px = static_cast<long>(f.gt_standing);
  s.standing_masked_px = static_cast<long>(f.standing_masked);
  s.standing_masked = f.gt_standing > 0 ? double(f.standing_masked) / double(f.gt_standing) : -1.0;
  s.teddy_px = cv::countNonZero(teddy);
  s.teddy_masked_px = cv::countNonZero(mask & teddy);
  s.teddy_masked = s.teddy_px > 0 ? double(s.teddy_masked_px) / double(s.teddy_px) : -1.0;
  s.masked_share = double(f.est_dynamic) / double(mask.total());
  return s;
}

}  // namespace dynamap::dynbench
