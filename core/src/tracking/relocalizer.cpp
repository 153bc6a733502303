#include "dynamap/core/tracking/relocalizer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/core.hpp>

#include "dynamap/core/tracking/depth_sampling.hpp"

namespace dynamap {
namespace {

// Search radii around the landmarks' projections with the last known pose.
constexpr double kGuidedRadiiPx[] = {60.0, 160.0};
constexpr float kGuidedRatio = 0.9f;
constexpr int kRelocRansacIterations = 1000;
/// Keyframes within this many keyframe spacings (kf_max_translation_m, kf_max_rotation_deg) of
/// the last pose are candidates too.
constexpr double kNearLastFactor = 4.0;

/// For each query: best train index (or -1) under the ratio test, among trains allowed by `near`.
template <typename Near>
std::vector<int> bestMatches(const cv::Mat& dist, int max_hamming, float ratio, Near near) {
  std::vector<int> best(static_cast<std::size_t>(dist.rows), -1);
  for (int q = 0; q < dist.rows; ++q) {
    const int* row = dist.ptr<int>(q);
    int b1 = std::numeric_limits<int>::max(), b2 = b1, arg = -1;
    for (int t = 0; t < dist.cols; ++t) {
      if (row[t] >= b2 || !near(q, t)) continue;
      if (row[t] < b1) {
        b2 = b1;
        b1 = row[t];
        arg = t;
      } else {
        b2 = row[t];
      }
    }
    if (arg >= 0 && b1 <= max_hamming && static_cast<float>(b1) <= ratio * static_cast<float>(b2)) {
      best[static_cast<std::size_t>(q)] = arg;
    }
  }
  return best;
}

}  // namespace

double seenThroughShare(const std::vector<Eigen::Vector3d>& points_W, const Eigen::Isometry3d& T_W_C,
                        const cv::Mat& depth_m, const PinholeCamera& camera, double depth_min_m,
                        double depth_max_m, int* checked) {
  constexpr double kRelativeMargin = 0.10, kMarginM = 0.05;
  const Eigen::Isometry3d T_C_W = T_W_C.inverse();
  int compared = 0, seen_through = 0;
  for (const Eigen::Vector3d& p_W : points_W) {
    const Eigen::Vector3d p_C = T_C_W * p_W;
    if (p_C.z() < depth_min_m || p_C.z() > depth_max_m) continue;
    const Eigen::Vector2d uv = camera.project(p_C);
    if (uv.x() < 0 || uv.y() < 0 || uv.x() >= camera.width || uv.y() >= camera.height) continue;
    const double z = sampleDepth(depth_m, static_cast<float>(uv.x()), static_cast<float>(uv.y()),
                                 depth_min_m, depth_max_m);
    if (z <= 0.0) continue;
    ++compared;
    if (z > p_C.z() * (1.0 + kRelativeMargin) + kMarginM) ++seen_through;
  }
  if (checked != nullptr) *checked = compared;
  return compared > 0 ? static_cast<double>(seen_through) / compared : 0.0;
}

Relocalizer::Relocalizer(const TrackerConfig& config, const PoseOptimizer& optimizer)
    : config_(config), optimizer_(optimizer) {}

RelocalizationResult Relocalizer::relocalize(const OrbFeatures& features, const cv::Mat& depth_m,
                                             const LocalMap& map, const PinholeCamera& camera,
                                             const Eigen::Isometry3d& T_W_C_last) const {
  if (features.keypoints.size() < 6) return {};
  const LandmarkCandidates c = map.landmarksOf(candidateKeyframes(map, T_W_C_last));
  const int fewest = config_.reloc_near_last_min_inliers > 0
                         ? std::min(config_.reloc_min_inliers, config_.reloc_near_last_min_inliers)
                         : config_.reloc_min_inliers;
  return relocalizeNear(features, depth_m, c, camera, T_W_C_last, &T_W_C_last, fewest);
}

// The newest keyframes, and as many again of those nearest the last pose: on a revisit that
// reuses the map the keyframes in view are old ones, and the newest see another part of it.
std::vector<std::uint64_t> Relocalizer::candidateKeyframes(
    const LocalMap& map, const Eigen::Isometry3d& T_W_C_last) const {
  std::vector<std::uint64_t> ids = map.newestKeyframes(config_.reloc_keyframes);
  const std::vector<std::uint64_t> near =
      map.keyframesNear(T_W_C_last, kNearLastFactor * config_.kf_max_translation_m,
                        kNearLastFactor * config_.kf_max_rotation_deg);
  const std::size_t most = ids.size() + static_cast<std::size_t>(config_.reloc_keyframes);
  for (const auto k : near) {
    if (ids.size() >= most) break;
    if (std::find(ids.begin(), ids.end(), k) == ids.end()) ids.push_back(k);
  }
  return ids;
}

RelocalizationResult Relocalizer::relocalizeAgainst(const OrbFeatures& features,
                                                    const cv::Mat& depth_m,
                                                    const LandmarkCandidates& c,
                                                    const PinholeCamera& camera,
                                                    const Eigen::Isometry3d& T_W_C_hint,
                                                    int fewest_matches) const {
  return relocalizeNear(features, depth_m, c, camera, T_W_C_hint, nullptr, fewest_matches);
}

RelocalizationResult Relocalizer::relocalizeNear(const OrbFeatures& features,
                                                 const cv::Mat& depth_m,
                                                 const LandmarkCandidates& c,
                                                 const PinholeCamera& camera,
                                                 const Eigen::Isometry3d& T_W_C_hint,
                                                 const Eigen::Isometry3d* T_W_C_last,
                                                 int fewest_matches) const {
  if (features.keypoints.size() < 6 || c.ids.size() < 6) return {};
  RelocalizationResult best;  // the pose with most inliers of the tries that had too few
  cv::Mat dist;
  cv::batchDistance(features.descriptors, c.descriptors, dist, CV_32S, cv::noArray(),
                    cv::NORM_HAMMING);

  // 1) Guided: landmarks projected with the last known pose, matched within a radius.
  const Eigen::Isometry3d T_C_W = T_W_C_hint.inverse();
  std::vector<Eigen::Vector2d> proj(c.points.size());
  std::vector<char> visible(c.points.size(), 0);
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    const Eigen::Vector3d p_C = T_C_W * c.points[i];
    if (p_C.z() <= 0.1) continue;
    proj[i] = camera.project(p_C);
    visible[i] = 1;
  }
  for (const double radius_px : kGuidedRadiiPx) {
    const double r2 = radius_px * radius_px;
    const auto guided =
        bestMatches(dist, config_.reloc_max_hamming, kGuidedRatio, [&](int q, int t) {
          const auto ti = static_cast<std::size_t>(t);
          if (!visible[ti]) return false;
          const cv::Point2f& p = features.keypoints[static_cast<std::size_t>(q)].pt;
          return (proj[ti] - Eigen::Vector2d(p.x, p.y)).squaredNorm() < r2;
        });
    RelocalizationResult result =
        solve(features, dist, depth_m, c.ids, c.points, guided, T_W_C_last, fewest_matches);
    if (result.ok) return result;
    if (result.inliers > best.inliers) best = std::move(result);
  }
  // 2) Global: any landmark of the recent keyframes, ratio test and mutual nearest neighbours.
  auto global = bestMatches(dist, config_.reloc_max_hamming,
                            static_cast<float>(config_.reloc_ratio), [](int, int) { return true; });
  for (std::size_t q = 0; q < global.size(); ++q) {
    if (global[q] < 0) continue;
    double min_val = 0.0;
    cv::Point min_loc;
    cv::minMaxLoc(dist.col(global[q]), &min_val, nullptr, &min_loc);
    if (min_loc.y != static_cast<int>(q)) global[q] = -1;
  }
  RelocalizationResult result =
      solve(features, dist, depth_m, c.ids, c.points, global, T_W_C_last, fewest_matches);
  return result.ok || result.inliers > best.inliers ? result : best;
}

RelocalizationResult Relocalizer::solve(const OrbFeatures& features, const cv::Mat& dist,
                                        const cv::Mat& depth_m,
                                        const std::vector<std::uint64_t>& ids,
                                        const std::vector<Eigen::Vector3d>& points,
                                        const std::vector<int>& match,
                                        const Eigen::Isometry3d* T_W_C_last,
                                        int fewest_matches) const {
  RelocalizationResult result;
  std::vector<PoseCorrespondence> corr;
  std::vector<int> query_index;
  // One query per landmark: the closest in descriptor distance (the same corner is often
  // detected at several pyramid levels).
  std::vector<int> owner(ids.size(), -1);
  for (std::size_t q = 0; q < match.size(); ++q) {
    if (match[q] < 0) continue;
    int& o = owner[static_cast<std::size_t>(match[q])];
    if (o < 0 || dist.at<int>(static_cast<int>(q), match[q]) < dist.at<int>(o, match[q])) {
      o = static_cast<int>(q);
    }
  }
  for (std::size_t q = 0; q < match.size(); ++q) {
    if (match[q] < 0 || owner[static_cast<std::size_t>(match[q])] != static_cast<int>(q)) continue;
    const cv::Point2f& p = features.keypoints[q].pt;
    PoseCorrespondence pc;
    pc.p_W = points[static_cast<std::size_t>(match[q])];
    pc.px = Eigen::Vector2d(p.x, p.y);
    pc.depth_m = sampleDepth(depth_m, p.x, p.y, config_.depth_min_m, config_.depth_max_m);
    pc.sigma_scale = std::pow(config_.orb_scale_factor, features.keypoints[q].octave);
    corr.push_back(pc);
    query_index.push_back(static_cast<int>(q));
  }
  if (static_cast<int>(corr.size()) < fewest_matches) return result;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  std::vector<std::uint8_t> inlier;
  if (!optimizer_.ransac(corr, T_W_C, inlier, false, kRelocRansacIterations)) return result;
  const int count = optimizer_.refine(corr, T_W_C, inlier);
  result.ok = enoughInliers(count, T_W_C, T_W_C_last);
  result.T_W_C = T_W_C;
  result.inliers = count;
  for (std::size_t i = 0; i < corr.size(); ++i) {
    if (!inlier[i]) continue;
    const auto q = static_cast<std::size_t>(query_index[i]);
    result.landmark_ids.push_back(ids[static_cast<std::size_t>(match[q])]);
    result.px.push_back(features.keypoints[q].pt);
  }
  return result;
}

bool Relocalizer::enoughInliers(int inliers, const Eigen::Isometry3d& T_W_C,
                                const Eigen::Isometry3d* T_W_C_last) const {
  if (inliers >= config_.reloc_min_inliers) return true;
  if (T_W_C_last == nullptr || config_.reloc_near_last_min_inliers <= 0 ||
      inliers < config_.reloc_near_last_min_inliers) {
    return false;
  }
  constexpr double kNearM = 0.10, kNearRad = 10.0 * M_PI / 180.0;
  const Eigen::Isometry3d step = T_W_C_last->inverse() * T_W_C;
  return step.translation().norm() <= kNearM &&
         Eigen::AngleAxisd(step.linear()).angle() <= kNearRad;
}

}  // namespace dynamap
