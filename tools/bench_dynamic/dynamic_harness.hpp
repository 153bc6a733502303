#pragma once
// Evaluation harness for motion-area removal on teddy_dyn_dev without the tracker: loads
// frames, builds LK matches between consecutive frames, scores masks against ground truth.
// Header-only; shared by tools/bench_dynamic/dyn_bench.cpp and tests/dynamic.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "dynamap/core/frame.hpp"
#include "dynamap/core/motion_filter.hpp"

namespace dynamap::dynbench {

struct StampedFile {
  double stamp = 0.0;
  std::string file;
};

inline std::vector<StampedFile> readList(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::vector<StampedFile> out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    StampedFile f;
    if (ss >> f.stamp >> f.file) out.push_back(f);
  }
  return out;
}

inline const StampedFile& nearest(const std::vector<StampedFile>& list, double stamp) {
  return *std::min_element(list.begin(), list.end(), [&](const auto& a, const auto& b) {
    return std::abs(a.stamp - stamp) < std::abs(b.stamp - stamp);
  });
}

struct SequenceFrame {
  RgbdFrame frame;
  cv::Mat gray;
  cv::Mat gt_mask;     ///< 255 moving person, 128 standing person
  cv::Mat teddy_mask;  ///< 255 = teddy (and the top of its box)
};

/// teddy_dyn_dev: rgb/depth/mask lists (depth and mask associated by nearest stamp), the
/// ground-truth poses, and the teddy as a world-frame ball (centre measured from frame 0:
/// median of the near pixels on the teddy back-projected with the ground-truth pose).
class DynSequence {
 public:
  explicit DynSequence(const std::filesystem::path& dir)
      : dir_(dir),
        rgb_(readList(dir / "rgb.txt")),
        depth_(readList(dir / "depth.txt")),
        mask_(readList(dir / "mask.txt")),
        gt_(readList(dir / "groundtruth.txt")) {
    std::ifstream in(dir / "groundtruth.txt");
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream ss(line);
      std::vector<double> v(8);
      for (auto& x : v) ss >> x;
      poses_.push_back(v);
    }
  }
  std::size_t size() const { return rgb_.size(); }

  SequenceFrame load(std::size_t i) const {
    SequenceFrame f;
    f.frame.index = i;
    f.frame.timestamp_s = rgb_[i].stamp;
    f.frame.bgr = cv::imread((dir_ / rgb_[i].file).string(), cv::IMREAD_COLOR);
    const cv::Mat d16 =
        cv::imread((dir_ / nearest(depth_, rgb_[i].stamp).file).string(), cv::IMREAD_UNCHANGED);
    d16.convertTo(f.frame.depth_m, CV_32F, 1.0 / 5000.0);
    f.gt_mask =
        cv::imread((dir_ / nearest(mask_, rgb_[i].stamp).file).string(), cv::IMREAD_GRAYSCALE);
    if (f.frame.bgr.empty() || d16.empty() || f.gt_mask.empty()) {
      throw std::runtime_error("cannot read frame " + std::to_string(i) + " of " + dir_.string());
    }
    cv::cvtColor(f.frame.bgr, f.gray, cv::COLOR_BGR2GRAY);
    f.teddy_mask = teddyMask(f.frame.depth_m, rgb_[i].stamp, f.gt_mask);
    return f;
  }

  /// Ground-truth camera-to-world pose nearest to `stamp` (false if none within 0.02 s).
  bool gtPose(double stamp, Eigen::Isometry3d* T_W_C) const {
    if (poses_.empty()) return false;
    const auto& p =
        *std::min_element(poses_.begin(), poses_.end(), [&](const auto& a, const auto& b) {
          return std::abs(a[0] - stamp) < std::abs(b[0] - stamp);
        });
    if (std::abs(p[0] - stamp) > 0.02) return false;
    T_W_C->setIdentity();
    T_W_C->linear() = Eigen::Quaterniond(p[7], p[4], p[5], p[6]).normalized().toRotationMatrix();
    T_W_C->translation() = Eigen::Vector3d(p[1], p[2], p[3]);
    return true;
  }

 private:
  cv::Mat teddyMask(const cv::Mat& depth, double stamp, const cv::Mat& gt) const {
    const auto& p =
        *std::min_element(poses_.begin(), poses_.end(), [&](const auto& a, const auto& b) {
          return std::abs(a[0] - stamp) < std::abs(b[0] - stamp);
        });
    const Eigen::Quaterniond q(p[7], p[4], p[5], p[6]);
    const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
    const Eigen::Vector3d t(p[1], p[2], p[3]), centre(-1.7037, 0.0019, 1.2005);
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
  std::vector<StampedFile> rgb_, depth_, mask_, gt_;
  std::vector<std::vector<double>> poses_;
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

inline MaskScore scoreMask(const cv::Mat& mask_in, const cv::Mat& gt, const cv::Mat& teddy) {
  const cv::Mat mask = mask_in.empty() ? cv::Mat::zeros(gt.size(), CV_8UC1) : (mask_in > 0);
  const cv::Mat moving = gt == 255, standing = gt == 128;
  MaskScore s;
  const int n_moving = cv::countNonZero(moving);
  s.moving_visible = n_moving > 0;
  const int inter = cv::countNonZero(mask & moving);
  const int uni = cv::countNonZero(mask | moving);
  s.iou = uni > 0 ? double(inter) / uni : 0.0;
  const int n_standing = cv::countNonZero(standing);
  s.standing_masked =
      n_standing > 0 ? double(cv::countNonZero(mask & standing)) / n_standing : -1.0;
  const int n_teddy = cv::countNonZero(teddy);
  s.teddy_masked = n_teddy > 0 ? double(cv::countNonZero(mask & teddy)) / n_teddy : -1.0;
  s.masked_share = double(cv::countNonZero(mask)) / double(mask.total());
  s.standing_px = n_standing;
  s.standing_masked_px = cv::countNonZero(mask & standing);
  s.teddy_px = n_teddy;
  s.teddy_masked_px = cv::countNonZero(mask & teddy);
  return s;
}

}  // namespace dynamap::dynbench
