// A saved map's landmarks keep the keyframe counts of the runs that saved it: the motion filter's
// pose prior (tracking.static_prior_min_keyframes) takes them from the first tracked frame of a
// run in that map. Started at 0, no landmark counted until this run's keyframes saw it twice, and
// a run that reuses the map makes almost none: the motion filter went without its pose, found no
// mover by geometry (a pushed chair, anchors, seen-through regions), and teddy played backward in
// the map of a run without the chair drifted 6.3 cm with 35 new keyframes (0.97 cm, 5 kept).
#include <gtest/gtest.h>

#include "dynamap/core/tracking/local_map.hpp"

namespace dynamap {
namespace {

TEST(LocalMapRestore, ASavedMapsLandmarksKeepTheirKeyframeCountsAndThisRunsAddToThem) {
  MapContents saved;
  for (int i = 0; i < 2; ++i) {
    Landmark lm;
    lm.p_W = Eigen::Vector3d(0.1 * i, 0.0, 2.0);
    lm.descriptor = cv::Mat::zeros(1, 32, CV_8U);
    lm.keyframes = 3 + i;  // seen by three and four keyframes of the earlier run
    saved.landmarks.push_back(lm);
  }
  MapKeyframe kf;
  kf.observations = {{0, Eigen::Vector2d(320, 240), 2.0}, {1, Eigen::Vector2d(347, 240), 2.0}};
  saved.keyframes.push_back(kf);
  LocalMap map;
  map.restore(saved);
  std::vector<int> counts;
  map.keyframeCounts({0, 1}, counts);
  EXPECT_EQ(counts, (std::vector<int>{3, 4}));
  map.addKeyframe(1.0, Eigen::Isometry3d::Identity(), {{0, Eigen::Vector2d(320, 240), 2.0}});
  map.keyframeCounts({0, 1}, counts);
  EXPECT_EQ(counts, (std::vector<int>{4, 4}));
}

}  // namespace
}  // namespace dynamap
