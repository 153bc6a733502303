// maskSeenLater (mask_lookahead.hpp): a later frame's mask, carried back into a keyframe through
// the keyframe's depth and both poses. Analytic scene: a wall 3 m away, a person (a board) 1.5 m
// away; between the keyframe and the later frame the camera moves 5 cm sideways and the person
// 3 cm, and a second mover steps in front of the wall.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "dynamap/mapping/mask_lookahead.hpp"

namespace dynamap::mask_lookahead_test {
namespace {

struct Board {
  double x0, x1, y0, y1, z;  ///< world rectangle at depth z (camera looks along +z)
};

/// Depth (and mask of `masked` boards) of a camera at `T_W_C` (translation only).
void render(const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C,
            const std::vector<Board>& boards, const std::vector<bool>& masked, cv::Mat* depth_m,
            cv::Mat* mask) {
  *depth_m = cv::Mat(camera.height, camera.width, CV_32FC1, cv::Scalar(3.0f));  // the wall
  *mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  const Eigen::Vector3d c = T_W_C.translation();
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3d ray = camera.backProject(u, v, 1.0);
      for (std::size_t b = 0; b < boards.size(); ++b) {
        const double s = boards[b].z - c.z();
        const Eigen::Vector3d p = c + s * ray;
        if (p.x() < boards[b].x0 || p.x() > boards[b].x1 || p.y() < boards[b].y0 ||
            p.y() > boards[b].y1 || s >= depth_m->at<float>(v, u)) {
          continue;
        }
        depth_m->at<float>(v, u) = static_cast<float>(s);
        mask->at<std::uint8_t>(v, u) = masked[b] ? 255 : 0;
      }
    }
  }
}

TEST(MaskLookahead, MarksTheMoverALaterMaskCoversAndNotWhatMovedInFrontLater) {
  PinholeCamera camera;
  const Board person{-0.2, 0.1, -0.5, 0.6, 1.5};
  const Board newcomer{0.5, 0.8, -0.3, 0.5, 1.0};  // only in the later frame
  Eigen::Isometry3d T_W_K = Eigen::Isometry3d::Identity(), T_W_L = T_W_K;
  T_W_L.translation() = Eigen::Vector3d(0.05, 0.0, 0.0);
  cv::Mat depth_k, mask_k, depth_l, mask_l;
  render(camera, T_W_K, {person}, {true}, &depth_k, &mask_k);  // mask_k: the truth
  Board moved = person;
  moved.x0 += 0.03;
  moved.x1 += 0.03;
  render(camera, T_W_L, {moved, newcomer}, {true, true}, &depth_l, &mask_l);

  const cv::Mat marked = maskSeenLater(camera, depth_k, T_W_K, depth_l, T_W_L, mask_l);
  ASSERT_EQ(marked.size(), depth_k.size());
  const double person_px = cv::countNonZero(mask_k);
  const double wall_px = static_cast<double>(mask_k.total()) - person_px;
  // The person moved 3 cm (about 11 px at 1.5 m): all but that sliver is marked.
  EXPECT_GT(cv::countNonZero(marked & mask_k) / person_px, 0.85);
  // The wall the newcomer hides later, and the wall the person moved over, are not.
  EXPECT_LT(cv::countNonZero(marked & ~mask_k) / wall_px, 0.002);

  // Without a later mask nothing is marked; an empty keyframe depth marks nothing either.
  EXPECT_EQ(cv::countNonZero(maskSeenLater(camera, depth_k, T_W_K, depth_l, T_W_L,
                                           cv::Mat::zeros(mask_l.size(), CV_8UC1))),
            0);
  const cv::Mat no_depth = cv::Mat::zeros(depth_k.size(), CV_32FC1);
  EXPECT_EQ(cv::countNonZero(maskSeenLater(camera, no_depth, T_W_K, depth_l, T_W_L, mask_l)), 0);
}

TEST(MaskLookahead, ALaterMaskTrimmedOffItsWallCarriesNoMarginBack) {
  // The later mask as the motion filter makes it: the person grown by a 3 px margin, which lies
  // on the wall around him. Carried back as it is, the margin lands on the keyframe's wall;
  // trimmed first over the later frame's own depth (marginNotBehind), it does not, and the
  // person is still covered but for the sliver he moved.
  PinholeCamera camera;
  const Board person{-0.2, 0.1, -0.5, 0.6, 1.5};
  Eigen::Isometry3d T_W_K = Eigen::Isometry3d::Identity(), T_W_L = T_W_K;
  T_W_L.translation() = Eigen::Vector3d(0.05, 0.0, 0.0);
  cv::Mat depth_k, mask_k, depth_l, mask_l;
  render(camera, T_W_K, {person}, {true}, &depth_k, &mask_k);
  Board moved = person;
  moved.x0 += 0.03;
  moved.x1 += 0.03;
  render(camera, T_W_L, {moved}, {true}, &depth_l, &mask_l);
  cv::Mat grown;
  cv::dilate(mask_l, grown, cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));

  const auto carried = [&](const cv::Mat& later) {
    return maskSeenLater(camera, depth_k, T_W_K, depth_l, T_W_L, later);
  };
  const cv::Mat whole = carried(grown);
  const cv::Mat trimmed = carried(marginNotBehind(grown, depth_l, 3, 0.1));
  EXPECT_GT(cv::countNonZero(whole & ~mask_k), 1500);  // the margin, on the wall
  EXPECT_LT(cv::countNonZero(trimmed & ~mask_k), 50);
  const double person_px = cv::countNonZero(mask_k);
  EXPECT_GT(cv::countNonZero(trimmed & mask_k) / person_px, 0.85);
}

TEST(MarginNotBehind, TheMarginLeavesTheWallBehindButKeepsTheOutlineHolesFloorAndSlivers) {
  // A person 2 m away (100 x 200 px) before a wall at 4 m, masked as the motion filter does: his
  // pixels 2 px short on every side, grown by 3 px. A hole without depth touches his right side,
  // the floor at 2.05 m his feet; a later frame's sliver (4 px wide) lies on the wall far off.
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(4.f));
  depth(cv::Rect(200, 100, 100, 200)).setTo(2.f);
  depth(cv::Rect(300, 150, 20, 20)).setTo(0.f);
  depth(cv::Rect(150, 300, 200, 30)).setTo(2.05f);
  cv::Mat mask = cv::Mat::zeros(depth.size(), CV_8UC1);
  mask(cv::Rect(202, 102, 96, 196)).setTo(255);
  cv::dilate(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));
  mask(cv::Rect(500, 50, 4, 60)).setTo(255);
  const cv::Mat out = marginNotBehind(mask, depth, 3, 0.1);
  EXPECT_EQ(cv::countNonZero(out & ~mask), 0);  // never more than the mask
  ASSERT_EQ(mask.at<uchar>(240, 199), 255);
  EXPECT_EQ(out.at<uchar>(240, 199), 0);    // the margin on the wall
  EXPECT_EQ(out.at<uchar>(240, 200), 255);  // his outline, which the core missed
  EXPECT_EQ(out.at<uchar>(160, 300), 255);  // the hole beside him
  EXPECT_EQ(out.at<uchar>(300, 250), 255);  // the floor at his feet
  EXPECT_EQ(out.at<uchar>(80, 501), 255);   // the sliver: no core near it
  // Of the wall, only the sliver stays: the margin on it (1 px wide, 472 px) is gone.
  EXPECT_EQ(cv::countNonZero((depth > 3.f) & out), 4 * 60);
  EXPECT_GT(cv::countNonZero((depth > 3.f) & mask), 4 * 60 + 400);
  // behind_m = 0: the mask as it is.
  EXPECT_EQ(cv::countNonZero(marginNotBehind(mask, depth, 3, 0.0) != mask), 0);
}

}  // namespace
}  // namespace dynamap::mask_lookahead_test
