// The detector thread's read-ahead: a frame handed over as soon as it is read gives the same
// detections as the frame handed over when it is begun; a frame read ahead but never begun is
// dropped, and a frame is never detected twice.
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "dynamap/core/dynamic/detector_worker.hpp"

namespace dynamap {
namespace {

/// Reports one box whose x is the image's grey value, slowly (as a real network is).
class GreyDetector : public ObjectDetector {
 public:
  explicit GreyDetector(std::atomic<int>* calls) : calls_(calls) {}
  std::vector<Detection> detect(const cv::Mat& bgr) override {
    ++*calls_;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    const float grey = static_cast<float>(bgr.at<cv::Vec3b>(0, 0)[0]);
    return {Detection{cv::Rect2f(grey, 0.f, 10.f, 10.f), 0, 0.9f}};
  }

 private:
  std::atomic<int>* calls_;
};

cv::Mat greyImage(int value) { return cv::Mat(8, 8, CV_8UC3, cv::Scalar::all(value)); }

struct Taken {
  long frame_no;
  float box_x;
};

/// The lockstep protocol of DynamicMotionFilter::beginFrame() over `frames` frames: take the
/// last frame's detections, hand this one over; with `read_ahead` the next frame follows at once.
std::vector<Taken> runLockstep(int frames, bool read_ahead, std::atomic<int>* calls) {
  DetectorWorker worker(std::make_unique<GreyDetector>(calls), 0, [](double) {});
  std::vector<Taken> taken;
  for (int k = 0; k < frames; ++k) {
    DetectorWorker::Result r;
    if (worker.take(&r, true)) taken.push_back({r.frame_no, r.detections.at(0).box.x});
    EXPECT_TRUE(worker.submit(greyImage(10 * k), k, 0.1 * k, true));
    if (read_ahead && k + 1 < frames) {
      worker.prefetch(greyImage(10 * (k + 1)), 0.1 * (k + 1));
      // The next frame is detected before it is begun (within 2 s: the detector takes 5 ms).
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
      while (calls->load() < k + 2 && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
      EXPECT_EQ(calls->load(), k + 2) << "frame " << k + 1 << " was not read ahead";
    }
  }
  DetectorWorker::Result r;
  if (worker.take(&r, true)) taken.push_back({r.frame_no, r.detections.at(0).box.x});
  return taken;
}

TEST(DetectorWorker, ReadingAheadGivesEachFrameTheSameDetections) {
  std::atomic<int> calls_plain{0}, calls_ahead{0};
  const auto plain = runLockstep(8, false, &calls_plain);
  const auto ahead = runLockstep(8, true, &calls_ahead);
  ASSERT_EQ(plain.size(), 8u);
  ASSERT_EQ(ahead.size(), plain.size());
  for (std::size_t i = 0; i < plain.size(); ++i) {
    EXPECT_EQ(ahead[i].frame_no, plain[i].frame_no) << i;
    EXPECT_EQ(ahead[i].frame_no, static_cast<long>(i));
    EXPECT_FLOAT_EQ(ahead[i].box_x, plain[i].box_x) << i;
    EXPECT_FLOAT_EQ(ahead[i].box_x, 10.f * static_cast<float>(i));
  }
  EXPECT_EQ(calls_ahead.load(), 8);  // every frame detected once, none twice
}

TEST(DetectorWorker, AFrameReadAheadButNeverBegunIsDropped) {
  std::atomic<int> calls{0};
  DetectorWorker worker(std::make_unique<GreyDetector>(&calls), 0, [](double) {});
  worker.prefetch(greyImage(70), 0.7);  // read, then skipped (e.g. it had no depth)
  ASSERT_TRUE(worker.submit(greyImage(80), 5, 0.8, true));
  DetectorWorker::Result r;
  ASSERT_TRUE(worker.take(&r, true));
  EXPECT_EQ(r.frame_no, 5);
  EXPECT_FLOAT_EQ(r.detections.at(0).box.x, 80.f);
  EXPECT_FALSE(worker.take(&r, true));  // the dropped frame's result never comes
}

TEST(DetectorWorker, AReadAheadArrivingAfterItsFrameWasBegunIsNotDetectedAgain) {
  std::atomic<int> calls{0};
  DetectorWorker worker(std::make_unique<GreyDetector>(&calls), 0, [](double) {});
  ASSERT_TRUE(worker.submit(greyImage(30), 0, 0.3, true));
  worker.prefetch(greyImage(30), 0.3);  // the reading thread was late
  DetectorWorker::Result r;
  ASSERT_TRUE(worker.take(&r, true));
  EXPECT_EQ(r.frame_no, 0);
  EXPECT_EQ(calls.load(), 1);
}

}  // namespace
}  // namespace dynamap
