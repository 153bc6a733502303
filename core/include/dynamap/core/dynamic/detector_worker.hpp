#pragma once

#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/dynamic/object_detector.hpp"

namespace dynamap {

/// Runs the object detector on its own thread, in the order frames were handed over. Frames
/// carry the filter's frame number so that results can be aged.
///
/// Read-ahead: prefetch() hands over the frame that will be begun next as soon as it is read,
/// so the detector starts on it while the tracker still works on the current frame. The
/// frame's number is given when it is begun (submit() with its timestamp adopts it); a frame
/// read ahead that is never begun is dropped. Results are those of the same images either way.
///
/// submit(), take() and runNow() are called from one (tracking) thread; prefetch() may be
/// called from any thread.
class DetectorWorker {
 public:
  struct Result {
    std::vector<Detection> detections;
    long frame_no = -1;  ///< frame number they were computed on
    double stamp = 0.0;
  };

  /// `record_ms` receives each detection's duration (from the worker thread). `threads` > 0
  /// sets OpenCV's pool size first (before any tracking starts: see the .cpp).
  DetectorWorker(std::unique_ptr<ObjectDetector> detector, int threads,
                 std::function<void(double)> record_ms);
  ~DetectorWorker();
  DetectorWorker(const DetectorWorker&) = delete;
  DetectorWorker& operator=(const DetectorWorker&) = delete;

  /// Hands frame `frame_no` over if the thread is idle (or, with `wait`, once it is); false =
  /// skipped. A frame with this timestamp read ahead is adopted instead (true).
  bool submit(const cv::Mat& bgr, long frame_no, double stamp, bool wait);
  /// The frame that will be begun next (timestamp `stamp`); ignored while another one read
  /// ahead is pending. Thread-safe.
  void prefetch(const cv::Mat& bgr, double stamp);
  /// The newest finished result of a begun frame not yet taken (false if none); with `wait`,
  /// first waits for every begun frame in flight. Rethrows a detector error.
  bool take(Result* out, bool wait);
  /// Detects on the calling thread (synchronous mode), once the worker is idle.
  std::vector<Detection> runNow(const cv::Mat& bgr);

 private:
  static constexpr long kReadAhead = -1;  ///< frame number of a frame not begun yet
  struct Job {
    cv::Mat bgr;
    long frame_no = kReadAhead;
    double stamp = 0.0;
  };
  struct Done {
    Result result;
    std::exception_ptr error;
  };
  bool beganPending() const;      ///< a begun frame is queued or in flight
  bool readAheadPending() const;  ///< a frame read ahead is queued, in flight or done
  bool adoptReadAhead(long frame_no, double stamp);
  void loop();

  std::unique_ptr<ObjectDetector> detector_;
  std::function<void(double)> record_ms_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Job> jobs_;
  bool busy_ = false;
  long flight_frame_ = kReadAhead;  ///< the frame in flight (its number once begun)
  double flight_stamp_ = 0.0;
  bool flight_dropped_ = false;  ///< read ahead, then another frame was begun instead
  bool begun_any_ = false;
  double last_begun_stamp_ = 0.0;  ///< frames up to this one are begun: none is read ahead
  std::deque<Done> done_;
  bool stop_ = false;
  std::thread thread_;  // last: starts after every other member is ready
};

}  // namespace dynamap
