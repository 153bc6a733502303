#include "dynamap/core/tracking/landmark_search.hpp"

#include <cmath>
#include <limits>
#include <unordered_set>

namespace dynamap {

LandmarkCandidates landmarksWhere(const LandmarkCandidates& all,
                                  const std::function<bool(std::uint64_t)>& keep) {
  LandmarkCandidates out;
  for (std::size_t i = 0; i < all.ids.size(); ++i) {
    if (!keep(all.ids[i])) continue;
    out.ids.push_back(all.ids[i]);
    out.points.push_back(all.points[i]);
    out.descriptors.push_back(all.descriptors.row(static_cast<int>(i)));
  }
  return out;
}

LandmarkCandidates withoutLandmarks(const LandmarkCandidates& all,
                                    const std::vector<std::uint64_t>& ids) {
  const std::unordered_set<std::uint64_t> left_out(ids.begin(), ids.end());
  return landmarksWhere(all, [&](std::uint64_t id) { return left_out.count(id) == 0; });
}

std::vector<int> searchByProjection(const OrbFeatures& features, const std::vector<double>& depth_m,
                                    const LandmarkCandidates& candidates,
                                    const Eigen::Isometry3d& T_W_C, const PinholeCamera& camera,
                                    const LandmarkSearchParams& params) {
  const std::size_t n = features.keypoints.size();
  std::vector<int> match(n, -1);
  std::vector<int> best_dist(n, std::numeric_limits<int>::max());
  const Eigen::Isometry3d T_C_W = T_W_C.inverse();
  const double r2 = params.radius_px * params.radius_px;
  for (std::size_t c = 0; c < candidates.points.size(); ++c) {
    const Eigen::Vector3d p_C = T_C_W * candidates.points[c];
    if (p_C.z() <= 0.1) continue;
    const Eigen::Vector2d uv = camera.project(p_C);
    if (uv.x() < 0 || uv.y() < 0 || uv.x() >= camera.width || uv.y() >= camera.height) continue;
    const cv::Mat desc = candidates.descriptors.row(static_cast<int>(c));
    int b1 = std::numeric_limits<int>::max(), b2 = b1, arg = -1;
    for (std::size_t k = 0; k < n; ++k) {
      const cv::Point2f& p = features.keypoints[k].pt;
      const double dx = p.x - uv.x(), dy = p.y - uv.y();
      if (dx * dx + dy * dy > r2) continue;
      const double z = depth_m[k];
      if (z > 0.0 && std::abs(z - p_C.z()) > params.depth_tolerance * z) continue;
      const int d = static_cast<int>(
          cv::norm(desc, features.descriptors.row(static_cast<int>(k)), cv::NORM_HAMMING));
      if (d < b1) {
        b2 = b1;
        b1 = d;
        arg = static_cast<int>(k);
      } else if (d < b2) {
        b2 = d;
      }
    }
    if (arg < 0 || b1 > params.max_hamming) continue;
    if (b2 != std::numeric_limits<int>::max() &&
        static_cast<float>(b1) > params.ratio * static_cast<float>(b2)) {
      continue;
    }
    // One landmark per keypoint: the closest descriptor wins.
    const auto a = static_cast<std::size_t>(arg);
    if (b1 < best_dist[a]) {
      best_dist[a] = b1;
      match[a] = static_cast<int>(c);
    }
  }
  return match;
}

}  // namespace dynamap
