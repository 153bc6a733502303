#pragma once

#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "dynamap/core/tracker_config.hpp"

namespace dynamap {

/// ORB keypoints and their descriptors (one row per keypoint).
struct OrbFeatures {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  ///< CV_8U, 32 bytes per row
};

/// ORB over a scale pyramid, spread evenly: the image is cut into square cells and only the
/// strongest keypoint of each free cell is kept; cells still empty get the strongest FAST corner
/// found with a lower threshold (as ORB-SLAM does). Not thread-safe (cv::ORB keeps buffers).
class GridOrbExtractor {
 public:
  explicit GridOrbExtractor(const TrackerConfig& config);

  /// `allowed` CV_8UC1, non-zero = may detect there (empty = everywhere). Cells holding one of
  /// `occupied` (already tracked features) get no new keypoint.
  OrbFeatures extract(const cv::Mat& gray, const cv::Mat& allowed,
                      const std::vector<cv::Point2f>& occupied) const;
  /// Every ORB keypoint of the pyramid (no grid): for relocalization by descriptor matching.
  OrbFeatures extractAll(const cv::Mat& gray, const cv::Mat& allowed) const;
  /// More ORB keypoints, down to a lower FAST threshold (kf_reuse_orb_*), no grid: for finding
  /// known landmarks again by projection. Their keypoints won grid cells, often with a weak
  /// response, and are mostly missing from extractAll's strongest ones.
  OrbFeatures extractForSearch(const cv::Mat& gray, const cv::Mat& allowed) const;

 private:
  void fillEmptyCells(const cv::Mat& gray, const cv::Mat& allowed, int cols, int rows,
                      const std::vector<char>& taken, OrbFeatures& out) const;

  cv::Ptr<cv::ORB> orb_;
  cv::Ptr<cv::ORB> search_orb_;
  int cell_px_;
  int fill_threshold_;
};

}  // namespace dynamap
