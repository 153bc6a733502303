#include "dynamap/core/tracking/loop_verifier.hpp"

#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "dynamap/core/tracking/rgbd_residual.hpp"

namespace dynamap {
namespace {

/// For each query row: the reference row with the closest descriptor (or -1) under the
/// distance gate and the ratio test.
std::vector<int> ratioMatches(const cv::Mat& query, const cv::Mat& reference, int max_hamming,
                              float ratio) {
  std::vector<int> best(static_cast<std::size_t>(query.rows), -1);
  if (query.empty() || reference.rows < 2) return best;
  cv::Mat dist, idx;
  cv::batchDistance(query, reference, dist, CV_32S, idx, cv::NORM_HAMMING, 2);
  for (int q = 0; q < query.rows; ++q) {
    const int d1 = dist.at<int>(q, 0), d2 = dist.at<int>(q, 1);
    if (d1 <= max_hamming && static_cast<float>(d1) <= ratio * static_cast<float>(d2)) {
      best[static_cast<std::size_t>(q)] = idx.at<int>(q, 0);
    }
  }
  return best;
}

}  // namespace

LoopVerifier::LoopVerifier(const PinholeCamera& camera, const TrackerConfig& config,
                           const LoopVerifierParams& params)
    : camera_(camera), config_(config), params_(params), optimizer_(camera, config) {}

std::vector<PoseCorrespondence> LoopVerifier::correspondences(const LoopKeyframe& query,
                                                              const LoopKeyframe& reference) const {
  const std::vector<int> match =
      ratioMatches(query.descriptors, reference.descriptors, params_.max_hamming, params_.ratio);
  std::vector<PoseCorrespondence> corr;
  for (std::size_t q = 0; q < match.size(); ++q) {
    if (match[q] < 0) continue;
    const auto r = static_cast<std::size_t>(match[q]);
    const double z_ref = reference.depth_m[r];
    if (z_ref <= 0.0) continue;
    const cv::Point2f& pr = reference.keypoints[r].pt;
    const cv::KeyPoint& kq = query.keypoints[q];
    PoseCorrespondence c;
    c.p_W = camera_.backProject(pr.x, pr.y, z_ref);  // "world" = the reference camera
    c.px = Eigen::Vector2d(kq.pt.x, kq.pt.y);
    c.depth_m = query.depth_m[q];
    c.sigma_scale = std::pow(config_.orb_scale_factor, std::max(0, kq.octave));
    corr.push_back(c);
  }
  return corr;
}

int LoopVerifier::inliersAt(const std::vector<PoseCorrespondence>& corr,
                            const Eigen::Isometry3d& T_Cref_Cquery) const {
  const Eigen::Isometry3d T_Cquery_Cref = T_Cref_Cquery.inverse();
  const double gate2 = config_.pnp_reprojection_px * config_.pnp_reprojection_px;
  int count = 0;
  for (const PoseCorrespondence& c : corr) {
    const Eigen::Vector3d p_C = T_Cquery_Cref * c.p_W;
    if (p_C.z() <= 0.05) continue;
    if ((camera_.project(p_C) - c.px).squaredNorm() > gate2 * c.sigma_scale * c.sigma_scale) {
      continue;
    }
    const double gate_z = 3.0 * depthSigma(config_.depth_sigma_coeff, c.depth_m);
    if (c.depth_m > 0.0 && std::abs(p_C.z() - c.depth_m) > gate_z) continue;
    ++count;
  }
  return count;
}

double LoopVerifier::hullShare(const std::vector<PoseCorrespondence>& corr,
                               const std::vector<std::uint8_t>& inlier) const {
  std::vector<cv::Point2f> points;
  for (std::size_t i = 0; i < corr.size(); ++i) {
    if (inlier[i]) {
      points.emplace_back(static_cast<float>(corr[i].px.x()), static_cast<float>(corr[i].px.y()));
    }
  }
  if (points.size() < 3) return 0.0;
  std::vector<cv::Point2f> hull;
  cv::convexHull(points, hull);
  return cv::contourArea(hull) / (static_cast<double>(camera_.width) * camera_.height);
}

std::optional<LoopConstraint> LoopVerifier::verify(
    const LoopKeyframe& query, const LoopKeyframe& candidate,
    const std::vector<const LoopKeyframe*>& neighbours) const {
  const std::vector<PoseCorrespondence> corr = correspondences(query, candidate);
  if (static_cast<int>(corr.size()) < params_.min_inliers) return std::nullopt;
  Eigen::Isometry3d T_Cc_Cq = Eigen::Isometry3d::Identity();
  std::vector<std::uint8_t> inlier;
  if (!optimizer_.ransac(corr, T_Cc_Cq, inlier, /*use_guess=*/false, params_.ransac_iterations)) {
    return std::nullopt;
  }
  LoopConstraint loop;
  loop.inliers = optimizer_.refine(corr, T_Cc_Cq, inlier);
  if (loop.inliers < params_.min_inliers) return std::nullopt;
  loop.hull_share = hullShare(corr, inlier);
  if (loop.hull_share < params_.min_hull_share) return std::nullopt;
  // The candidate's neighbours, placed by the odometry around it, must see the query there too.
  for (const LoopKeyframe* n : neighbours) {
    const Eigen::Isometry3d T_Cn_Cq = n->T_W_C.inverse() * candidate.T_W_C * T_Cc_Cq;
    if (inliersAt(correspondences(query, *n), T_Cn_Cq) >= params_.neighbour_min_inliers) {
      ++loop.consistent_neighbours;
    }
  }
  if (loop.consistent_neighbours < params_.min_consistent_neighbours) return std::nullopt;
  loop.query_id = query.id;
  loop.match_id = candidate.id;
  loop.T_Cmatch_Cquery = T_Cc_Cq;
  return loop;
}

}  // namespace dynamap
