#pragma once

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace dynamap::test {

/// Smooth 6-DoF camera path: ~2 cm and ~0.7 deg per frame for n = 60.
inline Eigen::Isometry3d smoothPath(int i, int n) {
  const double s = static_cast<double>(i) / n;
  const double two_pi = 2.0 * M_PI;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() =
      Eigen::Vector3d(0.25 * std::sin(two_pi * s), 0.10 * std::sin(2 * two_pi * s), 0.40 * s);
  const double deg = M_PI / 180.0;
  T.linear() = (Eigen::AngleAxisd(6 * deg * std::sin(two_pi * s), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(4 * deg * std::sin(two_pi * s + 1.0), Eigen::Vector3d::UnitX()) *
                Eigen::AngleAxisd(3 * deg * std::sin(two_pi * s + 2.0), Eigen::Vector3d::UnitZ()))
                   .toRotationMatrix();
  return T;
}

/// Root-mean-square translation error after a rigid (Horn/Umeyama, no scale) alignment of the
/// estimated positions onto the reference ones.
inline double ateRmseAligned(const std::vector<Eigen::Vector3d>& est,
                             const std::vector<Eigen::Vector3d>& ref) {
  const auto n = static_cast<Eigen::Index>(est.size());
  if (n < 3 || est.size() != ref.size()) return 1e9;
  Eigen::Matrix3Xd a(3, n), b(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    a.col(i) = est[static_cast<std::size_t>(i)];
    b.col(i) = ref[static_cast<std::size_t>(i)];
  }
  const Eigen::Matrix4d T = Eigen::umeyama(a, b, false);
  const Eigen::Matrix3Xd aligned =
      (T.topLeftCorner<3, 3>() * a).colwise() + T.topRightCorner<3, 1>();
  return std::sqrt((aligned - b).colwise().squaredNorm().mean());
}

/// One line "timestamp path" of a TUM rgb.txt / depth.txt.
struct TumEntry {
  double timestamp_s;
  std::string path;
};

inline std::vector<TumEntry> readTumList(const std::string& file) {
  std::vector<TumEntry> out;
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    TumEntry e;
    if (ss >> e.timestamp_s >> e.path) out.push_back(e);
  }
  return out;
}

/// TUM groundtruth.txt: timestamp -> T_W_C.
inline std::map<double, Eigen::Isometry3d> readTumGroundTruth(const std::string& file) {
  std::map<double, Eigen::Isometry3d> out;
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    double t, tx, ty, tz, qx, qy, qz, qw;
    if (!(ss >> t >> tx >> ty >> tz >> qx >> qy >> qz >> qw)) continue;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(tx, ty, tz);
    out.emplace(t, T);
  }
  return out;
}

/// Nearest entry of `sorted` to t within max_dt; nullptr if none.
template <typename Map>
const typename Map::mapped_type* nearest(const Map& sorted, double t, double max_dt) {
  auto it = sorted.lower_bound(t);
  const typename Map::mapped_type* best = nullptr;
  double best_dt = max_dt;
  if (it != sorted.end() && std::abs(it->first - t) <= best_dt) {
    best = &it->second;
    best_dt = std::abs(it->first - t);
  }
  if (it != sorted.begin()) {
    --it;
    if (std::abs(it->first - t) <= best_dt) best = &it->second;
  }
  return best;
}

}  // namespace dynamap::test
