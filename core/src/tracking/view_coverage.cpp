#include "dynamap/core/tracking/view_coverage.hpp"

#include <opencv2/imgproc.hpp>

#include "dynamap/core/tracking/depth_sampling.hpp"

namespace dynamap {
namespace {

int cellsAcross(int pixels) { return (pixels + kCoverageCellPx - 1) / kCoverageCellPx; }

/// Whether `view` (T_C_W: its pose inverted) saw p_W inside its image, in a static cell.
bool seesStatic(const PinholeCamera& camera, const CoverageView& view,
                const Eigen::Isometry3d& T_C_W, const Eigen::Vector3d& p_W) {
  const Eigen::Vector3d p_C = T_C_W * p_W;
  if (p_C.z() <= 0.0) return false;
  const Eigen::Vector2d px = camera.project(p_C);
  if (px.x() < 0.0 || px.y() < 0.0 || px.x() >= camera.width || px.y() >= camera.height) {
    return false;
  }
  if (view.static_cells.empty()) return true;
  const int cx = static_cast<int>(px.x()) / kCoverageCellPx;
  const int cy = static_cast<int>(px.y()) / kCoverageCellPx;
  return cx < view.static_cells.cols && cy < view.static_cells.rows &&
         view.static_cells.at<std::uint8_t>(cy, cx) != 0;
}

}  // namespace

cv::Mat staticCells(const cv::Mat& movers, int width, int height) {
  const cv::Size cells(cellsAcross(width), cellsAcross(height));
  if (movers.empty()) return cv::Mat(cells, CV_8U, cv::Scalar(1));
  cv::Mat moving_share;
  cv::resize(movers, moving_share, cells, 0.0, 0.0, cv::INTER_AREA);  // mean of 0/255 per cell
  cv::Mat still = moving_share < 128;
  return still / 255;
}

double uncoveredShare(const CoverageQuery& frame, const std::vector<CoverageView>& views) {
  const PinholeCamera& camera = *frame.camera;
  const cv::Mat& depth = *frame.depth_m;
  const bool any_movers = frame.movers != nullptr && !frame.movers->empty();
  std::vector<Eigen::Isometry3d> T_C_W;
  T_C_W.reserve(views.size());
  for (const CoverageView& view : views) T_C_W.push_back(view.T_W_C.inverse());
  int samples = 0, uncovered = 0;
  for (int v = kCoverageCellPx / 2; v < depth.rows; v += kCoverageCellPx) {
    for (int u = kCoverageCellPx / 2; u < depth.cols; u += kCoverageCellPx) {
      if (any_movers && frame.movers->at<std::uint8_t>(v, u) != 0) continue;
      const double z = sampleDepth(depth, static_cast<float>(u), static_cast<float>(v),
                                   frame.depth_min_m, frame.depth_max_m);
      if (z <= 0.0) continue;
      ++samples;
      const Eigen::Vector3d p_W = frame.T_W_C * camera.backProject(u, v, z);
      bool seen = false;
      for (std::size_t k = 0; k < views.size() && !seen; ++k) {
        seen = seesStatic(camera, views[k], T_C_W[k], p_W);
      }
      if (!seen) ++uncovered;
    }
  }
  return samples == 0 ? 0.0 : static_cast<double>(uncovered) / samples;
}

}  // namespace dynamap
