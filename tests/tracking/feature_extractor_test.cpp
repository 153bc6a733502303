// GridOrbExtractor (core/src/tracking/feature_extractor.cpp) on a rendered room: at most one
// keypoint a grid cell and most cells covered, none in masked pixels nor in occupied cells, and
// the low-threshold fill of cells ORB left empty.
#include <gtest/gtest.h>

#include <set>

#include <opencv2/imgproc.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/tracking/feature_extractor.hpp"
#include "synthetic_scene.hpp"

namespace dynamap {
namespace {

cv::Mat roomImage() {
  const PinholeCamera camera = cameraPreset("freiburg3");
  test::SyntheticScene scene(camera, 12);
  scene.addDefaultRoom();
  const test::RenderedFrame f = scene.render(Eigen::Isometry3d::Identity(), 0.0);
  cv::Mat gray;
  cv::cvtColor(f.bgr, gray, cv::COLOR_BGR2GRAY);
  return gray;
}

int cellOf(const cv::KeyPoint& k, int cell_px, int cols) {
  return (static_cast<int>(k.pt.y) / cell_px) * cols + static_cast<int>(k.pt.x) / cell_px;
}

TEST(FeatureExtractor, OneKeypointPerCellSpreadOverTheImage) {
  const cv::Mat gray = roomImage();
  const TrackerConfig config;
  const GridOrbExtractor orb(config);
  const OrbFeatures f = orb.extract(gray, cv::Mat(), {});
  const int cols = (gray.cols + config.grid_cell_px - 1) / config.grid_cell_px;
  const int rows = (gray.rows + config.grid_cell_px - 1) / config.grid_cell_px;
  ASSERT_EQ(f.descriptors.rows, static_cast<int>(f.keypoints.size()));
  EXPECT_EQ(f.descriptors.cols, 32);
  EXPECT_EQ(f.descriptors.type(), CV_8U);
  std::set<int> cells;
  for (const auto& k : f.keypoints) cells.insert(cellOf(k, config.grid_cell_px, cols));
  // One keypoint a cell: as many cells as keypoints.
  EXPECT_EQ(cells.size(), f.keypoints.size());
  // The room is textured everywhere but for a 20 px border ORB cannot describe: at least 80 %
  // of the 20 x 15 cells hold one.
  EXPECT_GE(static_cast<int>(f.keypoints.size()), cols * rows * 8 / 10)
      << f.keypoints.size() << " keypoints in " << cols * rows << " cells";
  // Every quarter of the image holds at least a fifth of them.
  int quarter[4] = {0, 0, 0, 0};
  for (const auto& k : f.keypoints) {
    ++quarter[(k.pt.x >= gray.cols / 2 ? 1 : 0) + (k.pt.y >= gray.rows / 2 ? 2 : 0)];
  }
  for (int q = 0; q < 4; ++q) {
    EXPECT_GE(quarter[q], static_cast<int>(f.keypoints.size()) / 5) << "quarter " << q;
  }
  // Without the grid, the whole ORB set: more keypoints, clustered several to a cell.
  const OrbFeatures all = orb.extractAll(gray, cv::Mat());
  EXPECT_GT(all.keypoints.size(), f.keypoints.size());
  EXPECT_EQ(all.descriptors.rows, static_cast<int>(all.keypoints.size()));
}

TEST(FeatureExtractor, MaskedPixelsAndOccupiedCellsGetNoKeypoint) {
  const cv::Mat gray = roomImage();
  const TrackerConfig config;
  const GridOrbExtractor orb(config);
  // Forbidden: the left half and a 200 x 150 block in the right half.
  cv::Mat allowed(gray.size(), CV_8UC1, cv::Scalar(255));
  allowed.colRange(0, 320).setTo(0);
  const cv::Rect block(400, 200, 200, 150);
  allowed(block).setTo(0);
  // ORB applies the mask per pyramid level at that level's scale: a keypoint of a coarse level
  // may sit up to about one level pixel (<= 4 px at level 7) inside; none farther.
  const int kSlackPx = 4;
  for (const OrbFeatures& f : {orb.extract(gray, allowed, {}), orb.extractAll(gray, allowed)}) {
    ASSERT_GT(f.keypoints.size(), 50u);
    for (const auto& k : f.keypoints) {
      EXPECT_GE(k.pt.x, 320 - kSlackPx) << k.pt << " level " << k.octave;
      const bool inside = k.pt.x > block.x + kSlackPx &&
                          k.pt.x < block.x + block.width - kSlackPx &&
                          k.pt.y > block.y + kSlackPx && k.pt.y < block.y + block.height - kSlackPx;
      EXPECT_FALSE(inside) << k.pt << " level " << k.octave;
    }
  }
  // Cells holding an already tracked feature get nothing new.
  std::vector<cv::Point2f> occupied;
  for (int y = 0; y < gray.rows; y += config.grid_cell_px) {
    for (int x = 0; x < gray.cols / 2; x += config.grid_cell_px) {
      occupied.emplace_back(static_cast<float>(x + 5), static_cast<float>(y + 5));
    }
  }
  const OrbFeatures f = orb.extract(gray, cv::Mat(), occupied);
  ASSERT_GT(f.keypoints.size(), 50u);
  for (const auto& k : f.keypoints) EXPECT_GE(k.pt.x, gray.cols / 2) << k.pt;
}

TEST(FeatureExtractor, LowContrastCellsAreFilledByTheLowerFastThreshold) {
  // The room at a quarter of its contrast: ORB's FAST threshold (12) finds fewer corners; the
  // fill with threshold 5 gives back keypoints in the cells left empty.
  cv::Mat faint;
  roomImage().convertTo(faint, CV_8U, 0.25, 96.0);
  TrackerConfig config;
  config.orb_fast_threshold_min = 0;  // no fill
  const OrbFeatures without = GridOrbExtractor(config).extract(faint, cv::Mat(), {});
  config.orb_fast_threshold_min = 5;
  const OrbFeatures with = GridOrbExtractor(config).extract(faint, cv::Mat(), {});
  EXPECT_GE(with.keypoints.size(), without.keypoints.size() + 30)
      << without.keypoints.size() << " -> " << with.keypoints.size();
  ASSERT_EQ(with.descriptors.rows, static_cast<int>(with.keypoints.size()));
  const int cols = (faint.cols + config.grid_cell_px - 1) / config.grid_cell_px;
  std::set<int> cells;
  for (const auto& k : with.keypoints) cells.insert(cellOf(k, config.grid_cell_px, cols));
  EXPECT_EQ(cells.size(), with.keypoints.size());  // still one a cell
}

}  // namespace
}  // namespace dynamap
