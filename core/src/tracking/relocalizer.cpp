#include "dynamap/core/tracking/relocalizer.hpp"

#include <opencv2/features2d.hpp>

#include "dynamap/core/tracking/depth_sampling.hpp"

namespace dynamap {

Relocalizer::Relocalizer(const TrackerConfig& config, const PoseOptimizer& optimizer)
    : config_(config), optimizer_(optimizer) {}

RelocalizationResult Relocalizer::relocalize(const OrbFeatures& features, const cv::Mat& depth_m,
                                             const LocalMap& map) const {
  RelocalizationResult result;
  if (features.keypoints.size() < 6) return result;
  std::vector<std::uint64_t> ids;
  cv::Mat descriptors;
  std::vector<Eigen::Vector3d> points;
  map.relocCandidates(config_.reloc_keyframes, ids, descriptors, points);
  if (ids.size() < 6) return result;

  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(features.descriptors, descriptors, knn, 2);
  std::vector<PoseCorrespondence> corr;
  std::vector<int> query_index, train_index;
  std::vector<char> train_used(ids.size(), 0);
  for (const auto& m : knn) {
    if (m.empty() || m[0].distance > config_.reloc_max_hamming) continue;
    if (m.size() > 1 && m[0].distance > config_.reloc_ratio * m[1].distance) continue;
    if (train_used[static_cast<std::size_t>(m[0].trainIdx)]) continue;
    train_used[static_cast<std::size_t>(m[0].trainIdx)] = 1;
    const cv::Point2f& p = features.keypoints[static_cast<std::size_t>(m[0].queryIdx)].pt;
    PoseCorrespondence c;
    c.p_W = points[static_cast<std::size_t>(m[0].trainIdx)];
    c.px = Eigen::Vector2d(p.x, p.y);
    c.depth_m = sampleDepth(depth_m, p.x, p.y, config_.depth_min_m, config_.depth_max_m);
    corr.push_back(c);
    query_index.push_back(m[0].queryIdx);
    train_index.push_back(m[0].trainIdx);
  }
  if (static_cast<int>(corr.size()) < config_.reloc_min_inliers) return result;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  std::vector<std::uint8_t> inlier;
  if (!optimizer_.ransac(corr, T_W_C, inlier, false)) return result;
  const int count = optimizer_.refine(corr, T_W_C, inlier);
  if (count < config_.reloc_min_inliers) return result;
  result.ok = true;
  result.T_W_C = T_W_C;
  result.inliers = count;
  for (std::size_t i = 0; i < corr.size(); ++i) {
    if (!inlier[i]) continue;
    result.landmark_ids.push_back(ids[static_cast<std::size_t>(train_index[i])]);
    result.px.push_back(features.keypoints[static_cast<std::size_t>(query_index[i])].pt);
  }
  return result;
}

}  // namespace dynamap
