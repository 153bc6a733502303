#include "fusion_clusters.hpp"

#include <algorithm>
#include <numeric>

#include <opencv2/imgproc.hpp>

#include "dynamap/core/dynamic/depth_check.hpp"

namespace dynamap {

namespace {

constexpr int kInPlaceMinSamples = 20;  ///< depth samples needed to call a cluster in place
constexpr float kCarveMarginPx = 4.f;   ///< carveStatic()'s margin

int findRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

/// Groups the given points by single linkage with `radius`.
std::vector<std::vector<int>> clusterPoints(const std::vector<cv::Point2f>& pts,
                                            const std::vector<int>& ids, double radius) {
  std::vector<int> parent(ids.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t a = 0; a < ids.size(); ++a) {
    for (std::size_t b = a + 1; b < ids.size(); ++b) {
      if (cv::norm(pts[ids[a]] - pts[ids[b]]) <= radius) {
        parent[findRoot(parent, static_cast<int>(a))] = findRoot(parent, static_cast<int>(b));
      }
    }
  }
  std::vector<std::vector<int>> groups(ids.size());
  for (std::size_t a = 0; a < ids.size(); ++a)
    groups[findRoot(parent, static_cast<int>(a))].push_back(ids[a]);
  groups.erase(
      std::remove_if(groups.begin(), groups.end(), [](const auto& g) { return g.empty(); }),
      groups.end());
  return groups;
}

/// True if the earlier view (FusionEvidence::view) saw `region` (inside `roi`) in place: at
/// least cluster_max_consistent of its depth samples agree with that view.
bool inPlaceEarlier(const cv::Mat& depth_m, const cv::Mat& region, const cv::Rect& roi,
                    const FusionEvidence& evidence, const DynamicConfig& config) {
  const double share = config.cluster_max_consistent;
  if (share <= 0.0 || evidence.view == nullptr || !evidence.has_pose) return false;
  const DepthAgreement a = compareWithView(depth_m, region, roi, evidence.T_W_C, evidence.K,
                                           *evidence.view, DepthCheckOptions());
  return a.samples >= kInPlaceMinSamples && a.share(a.consistent) >= share;
}

/// True if most of the group's points with depth lie beyond `max_m` (0 = no range): there the
/// sensor's depth bends and jumps by tens of centimetres from view to view, and neither the
/// flags nor the earlier view's verdict say the surface moved.
bool beyondRange(const cv::Mat& depth_m, const std::vector<int>& group,
                 const std::vector<cv::Point2f>& points, double max_m) {
  if (max_m <= 0.0) return false;
  int with_depth = 0, far = 0;
  for (int i : group) {
    const cv::Point p(cvRound(points[i].x), cvRound(points[i].y));
    if (p.x < 0 || p.y < 0 || p.x >= depth_m.cols || p.y >= depth_m.rows) continue;
    const float z = depth_m.at<float>(p);
    if (z <= 0.f) continue;
    ++with_depth;
    far += z > max_m ? 1 : 0;
  }
  return 2 * far > with_depth && with_depth > 0;
}

/// Support: most tracked points around the cluster (its tight box and 10 px) must be dynamic,
/// else it is noise.
bool supported(const std::vector<int>& group, const cv::Rect& tight,
               const std::vector<cv::Point2f>& points) {
  const cv::Rect near = cv::Rect(tight.x - 10, tight.y - 10, tight.width + 20, tight.height + 20);
  int all = 0;
  for (const auto& p : points) all += near.contains(cv::Point(cvRound(p.x), cvRound(p.y)));
  return 2 * static_cast<int>(group.size()) >= all;
}

/// Where a cluster may grow: its tight box widened by cluster_box_margin (at least 40 px).
cv::Rect growthRoi(const cv::Rect& tight, const cv::Size& size, const DynamicConfig& config) {
  const double m = config.cluster_box_margin;
  const cv::Point2f c(tight.x + 0.5f * tight.width, tight.y + 0.5f * tight.height);
  const float hw = static_cast<float>(std::max(40.0, m * tight.width) / 2);
  const float hh = static_cast<float>(std::max(40.0, m * tight.height) / 2);
  return clampRect(cv::Rect2f(c.x - hw, c.y - hh, 2 * hw, 2 * hh), size);
}

/// The group's points flood-filled over continuous depth inside `roi`, never into objects or
/// planes; a full-image CV_8UC1 mask.
cv::Mat floodFromPoints(const cv::Mat& depth_m, const std::vector<int>& group, const cv::Rect& roi,
                        const std::vector<cv::Point2f>& points, const cv::Mat& claimed,
                        const FusionEvidence& evidence, const DynamicConfig& config) {
  cv::Mat flood = cv::Mat::zeros(roi.height + 2, roi.width + 2, CV_8UC1);
  flood(cv::Rect(1, 1, roi.width, roi.height)).setTo(1, claimed(roi));  // never grow into objects
  if (!evidence.planes.empty())
    flood(cv::Rect(1, 1, roi.width, roi.height)).setTo(1, evidence.planes(roi));
  const cv::Mat depth_roi = depth_m(roi).clone();
  const double step = config.flood_depth_step_m;
  for (int i : group) {
    const cv::Point s(cvRound(points[i].x) - roi.x, cvRound(points[i].y) - roi.y);
    if (!cv::Rect(0, 0, roi.width, roi.height).contains(s)) continue;
    if (depth_roi.at<float>(s) <= 0.f || flood.at<uchar>(s.y + 1, s.x + 1) != 0) continue;
    cv::floodFill(depth_roi, flood, s, cv::Scalar(), nullptr, cv::Scalar(step), cv::Scalar(step),
                  8 | cv::FLOODFILL_MASK_ONLY | (255 << 8));
  }
  cv::Mat filled = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  filled(roi).setTo(255, flood(cv::Rect(1, 1, roi.width, roi.height)) == 255);
  return filled;
}

}  // namespace

bool insideMask(const cv::Mat& mask, const cv::Point2f& p) {
  const int x = cvRound(p.x), y = cvRound(p.y);
  return x >= 0 && y >= 0 && x < mask.cols && y < mask.rows && mask.at<uchar>(y, x) != 0;
}

cv::Rect clampRect(const cv::Rect2f& r, const cv::Size& size) {
  return cv::Rect(cv::Point(cvFloor(r.x), cvFloor(r.y)),
                  cv::Point(cvCeil(r.br().x), cvCeil(r.br().y))) &
         cv::Rect(cv::Point(0, 0), size);
}

void carveStatic(cv::Mat& region, const cv::Rect& box, const std::vector<cv::Point2f>& points,
                 const std::vector<std::uint8_t>& dyn, const std::vector<std::uint8_t>& proven,
                 double radius) {
  if (radius <= 0.0 || box.area() <= 0) return;
  cv::Mat roi = region(box);
  cv::Mat dyn_free(box.size(), CV_8UC1, cv::Scalar(255));
  cv::Mat static_free(box.size(), CV_8UC1, cv::Scalar(255));
  int n_dyn = 0, n_static = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const cv::Point p(cvRound(points[i].x) - box.x, cvRound(points[i].y) - box.y);
    if (p.x < 0 || p.y < 0 || p.x >= box.width || p.y >= box.height) continue;
    if (roi.at<uchar>(p) == 0) continue;
    if (!dyn[i] && (i >= proven.size() || proven[i] == 0)) continue;
    (dyn[i] ? dyn_free : static_free).at<uchar>(p) = 0;
    ++(dyn[i] ? n_dyn : n_static);
  }
  if (n_dyn == 0 || n_static == 0) return;
  cv::Mat d_dyn, d_static;
  cv::distanceTransform(dyn_free, d_dyn, cv::DIST_L2, 3);
  cv::distanceTransform(static_free, d_static, cv::DIST_L2, 3);
  const cv::Mat remove =
      (d_static + kCarveMarginPx < d_dyn) & (d_static < static_cast<float>(radius));
  roi.setTo(0, remove);
}

int growClusters(const cv::Mat& depth_m, const std::vector<cv::Point2f>& points,
                 const std::vector<std::uint8_t>& dyn, const cv::Mat& claimed,
                 const FusionEvidence& evidence, const DynamicConfig& config, cv::Mat& mask) {
  std::vector<int> free_dyn;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (dyn[i] && !insideMask(claimed, points[i])) free_dyn.push_back(static_cast<int>(i));
  }
  int grown = 0;
  for (const auto& group : clusterPoints(points, free_dyn, config.cluster_radius_px)) {
    if (static_cast<int>(group.size()) < config.min_cluster_points) continue;
    std::vector<cv::Point2f> gp;
    for (int i : group) gp.push_back(points[i]);
    const cv::Rect tight = cv::boundingRect(gp);
    if (!supported(group, tight, points)) continue;
    if (beyondRange(depth_m, group, points, config.cluster_max_depth_m)) continue;
    const cv::Rect roi = growthRoi(tight, depth_m.size(), config);
    cv::Mat filled = floodFromPoints(depth_m, group, roi, points, claimed, evidence, config);
    carveStatic(filled, roi, points, dyn, evidence.proven_static, config.static_carve_radius_px);
    if (inPlaceEarlier(depth_m, filled, roi, evidence, config)) continue;
    filled = filled(roi);
    if (cv::countNonZero(filled) == 0) {  // no depth: the hull of the points
      std::vector<cv::Point> hull;
      for (const auto& p : gp) hull.emplace_back(cvRound(p.x), cvRound(p.y));
      cv::convexHull(std::vector<cv::Point>(hull), hull);
      cv::fillConvexPoly(mask, hull, 255);
    } else {
      mask(roi) |= filled;
    }
    ++grown;
  }
  return grown;
}

}  // namespace dynamap
