#pragma once
// Whether a point lies on the plane that a set of points around it spans (the visibility pass's
// test for floor that a mask took with a foot). Internal to dynamap_mapping.
#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

namespace dynamap {

struct PlaneTest {
  std::size_t min_points = 12;  ///< fewer support points: no plane
  float max_rms_m = 0.02f;      ///< the support's RMS distance to its best plane
  float max_offset_m = 0.03f;   ///< the point's distance to it (or twice the RMS, if larger)
};

/// Least-squares plane of `support` (principal axes); true if it is flat enough and `p` on it.
inline bool liesOnPlane(const std::vector<Eigen::Vector3f>& support, const Eigen::Vector3f& p,
                        const PlaneTest& test = {}) {
  if (support.size() < test.min_points) return false;
  Eigen::Vector3f mean = Eigen::Vector3f::Zero();
  for (const auto& q : support) mean += q;
  mean /= static_cast<float>(support.size());
  Eigen::Matrix3f cov = Eigen::Matrix3f::Zero();
  for (const auto& q : support) cov += (q - mean) * (q - mean).transpose();
  cov /= static_cast<float>(support.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> eig(cov);
  const float rms = std::sqrt(std::max(0.0f, eig.eigenvalues()(0)));
  if (rms > test.max_rms_m) return false;
  const float offset = std::abs(eig.eigenvectors().col(0).dot(p - mean));
  return offset <= std::max(test.max_offset_m, 2.0f * rms);
}

}  // namespace dynamap
