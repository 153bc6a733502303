// PlaceRecognizer (core/src/tracking/place_recognition.cpp) on random binary descriptors: 100
// keyframes of 200 descriptors each (so LSH chunks are built and merged); a query made of keyframe
// 37's descriptors with 8 of 256 bits flipped ranks keyframe 37 first, far ahead of the rest, and
// keyframes the caller leaves out never come back.
#include <gtest/gtest.h>

#include <random>

#include "dynamap/core/tracking/place_recognition.hpp"

namespace dynamap {
namespace {

cv::Mat randomDescriptors(int rows, std::mt19937& rng) {
  cv::Mat d(rows, 32, CV_8UC1);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < 32; ++c) d.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(byte(rng));
  }
  return d;
}

cv::Mat flipBits(const cv::Mat& in, int bits, std::mt19937& rng) {
  cv::Mat out = in.clone();
  std::uniform_int_distribution<int> bit(0, 255);
  for (int r = 0; r < out.rows; ++r) {
    for (int b = 0; b < bits; ++b) {
      const int k = bit(rng);
      out.at<std::uint8_t>(r, k / 8) ^= static_cast<std::uint8_t>(1 << (k % 8));
    }
  }
  return out;
}

class PlaceRecognitionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937 rng(5);
    for (int k = 0; k < 100; ++k) {
      keyframes_.push_back(randomDescriptors(200, rng));
      recognizer_.add(k, keyframes_.back());
    }
  }
  std::vector<cv::Mat> keyframes_;
  PlaceRecognizer recognizer_;
};

// Tolerance: at least 70 % of the 200 query descriptors vote for the true keyframe (LSH misses
// some), the runner-up gets at most 5 % (random 256-bit strings are ~128 bits apart).
TEST_F(PlaceRecognitionTest, RanksTheRevisitedKeyframeFirst) {
  std::mt19937 rng(9);
  const cv::Mat query = flipBits(keyframes_[37], 8, rng);
  const auto ranked = recognizer_.query(query, [](int) { return true; }, 5);
  ASSERT_GE(ranked.size(), 1u);
  EXPECT_EQ(ranked[0].keyframe, 37);
  EXPECT_GE(ranked[0].votes, 140);
  if (ranked.size() > 1) {
    EXPECT_LE(ranked[1].votes, 10);
  }
}

TEST_F(PlaceRecognitionTest, FindsKeyframesStillBruteForced) {
  std::mt19937 rng(10);
  const cv::Mat query = flipBits(keyframes_[99], 8, rng);  // the newest: not in an LSH chunk yet
  const auto ranked = recognizer_.query(query, [](int) { return true; }, 1);
  ASSERT_EQ(ranked.size(), 1u);
  EXPECT_EQ(ranked[0].keyframe, 99);
  EXPECT_GE(ranked[0].votes, 190);  // brute force misses none
}

TEST_F(PlaceRecognitionTest, LeavesOutWhatTheCallerExcludes) {
  std::mt19937 rng(11);
  const cv::Mat query = flipBits(keyframes_[37], 8, rng);
  const auto ranked = recognizer_.query(query, [](int k) { return k != 37; }, 5);
  for (const auto& c : ranked) {
    EXPECT_NE(c.keyframe, 37);
    EXPECT_LE(c.votes, 10);
  }
}

}  // namespace
}  // namespace dynamap
