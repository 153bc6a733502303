#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/core/dynamic/depth_check.hpp"
#include "dynamap/core/dynamic/epipolar_check.hpp"
#include "dynamap/core/dynamic/object_detector.hpp"
#include "dynamap/core/dynamic/region_fusion.hpp"
#include "dynamap/core/dynamic/support_planes.hpp"
#include "dynamap/core/dynamic_config.hpp"
#include "dynamap/core/motion_filter.hpp"
#include "dynamap/core/timing.hpp"

namespace dynamap {

class DetectorWorker;

/// Everything the last filter() call saw and decided (for debug images and benchmarks).
struct MotionDiagnostics {
  FeatureMatches matches;
  std::vector<std::uint8_t> epipolar_dynamic;  ///< geometric check per match
  std::vector<float> residual_px;              ///< its residual per match
  std::vector<std::uint8_t> match_is_dynamic;  ///< final flag per match
  EpipolarModel model = EpipolarModel::kNone;
  std::vector<Detection> detections;  ///< detector output after NMS
  std::vector<ObjectDecision> objects;
  int clusters = 0;
  int seen_through = 0;  ///< regions added by the dense check
  cv::Mat mask;
};

/// Motion-area removal: epipolar check + (optional) detector on a worker thread + fusion.
/// Per-stage durations go to "detector" (on the worker, one entry per detection), "epipolar",
/// "fusion", "dense_check" and "detector_wait" (how long filter() blocked on the detector). With
/// detector_async (default) beginFrame() only hands a frame over when the detector is idle
/// ("detector_skipped" counts the others), filter() uses the newest finished detections
/// ("detector_fresh" counts frames where a new result arrived, "detector_age" records the age
/// in ms of the detections used).
/// beginFrame()/filter() are called from one (tracking) thread; not otherwise thread-safe.
class DynamicMotionFilter : public MotionFilter {
 public:
  /// Throws DetectorError (naming the file) if the detector cannot be built,
  /// std::invalid_argument for a bad mode or class table.
  DynamicMotionFilter(const DynamicConfig& config, const PinholeCamera& camera,
                      TimingRecorder* timing);
  ~DynamicMotionFilter() override;
  DynamicMotionFilter(const DynamicMotionFilter&) = delete;
  DynamicMotionFilter& operator=(const DynamicMotionFilter&) = delete;

  void beginFrame(const RgbdFrame& frame) override;
  /// Lockstep runs (detector_async && detector_lockstep): the detector starts on `next` behind
  /// the frame in flight. Thread-safe.
  void prefetch(const RgbdFrame& next) override;
  MotionFilterOutput filter(const MotionFilterInput& input) override;

  const MotionDiagnostics& lastDiagnostics() const { return diagnostics_; }
  /// Stage durations of this filter (also forwarded to the recorder given at construction).
  const TimingRecorder& timings() const { return own_timing_; }
  const ClassTable& classTable() const { return classes_; }

 private:
  void record(const std::string& stage, double ms);
  std::vector<Detection> currentDetections(const RgbdFrame* frame, const FeatureMatches& m);
  bool lockstep() const;  ///< detector_async && detector_lockstep
  /// Lockstep: whether frame `frame_no` goes to the detector (detector_every_frames).
  bool detectedFrame(long frame_no) const;
  /// Moves the worker's newest finished detections (with `wait`, of the frame in flight) into
  /// latest_, if there are any.
  void takeDetections(bool wait);
  /// Moves the last frame's depth (pending_) into the history with its final pose, which this
  /// frame's input brings (input.has_prior); if that pose jumped from the one the last frame
  /// was checked with, the older views follow it (views_follow_pose_snaps).
  void keepLastDepth(const MotionFilterInput& input);
  /// The dense check (DynamicConfig::dense_check_frames): what the frame that many frames back
  /// saw through, outside fusion's objects, is added to the mask. No group starts on a support
  /// plane that the view saw at the same place (stillPlaneCells()), but groups grow into them.
  void addSeenThrough(const cv::Mat& depth_m, const FusionEvidence& evidence, FusionResult& fused);
  /// DynamicConfig::mover_tracks, in mode both.
  bool moverTracks() const;
  /// With moverTracks(): the regions the dense check's view saw through (moverDetections()),
  /// outside last frame's kept movers, the planes and the people's boxes (this frame's and last
  /// frame's, carried ones too), appended to `dets` as class-less movers. Records "movers".
  void addMovers(const cv::Mat& depth_m, const FusionEvidence& evidence,
                 std::vector<Detection>& dets);
  /// Pixels on the large planes of the frame (DynamicConfig::support_planes), found outside the
  /// detections and the last mask; empty when off or without depth.
  cv::Mat supportPlanePixels(const cv::Mat& depth_m, const std::vector<Detection>& dets);
  /// *background_fit: the camera motion was fitted on enough matches outside people and masks.
  EpipolarResult checkGeometry(const FeatureMatches& m, const cv::Mat& depth,
                               const std::vector<Detection>& dets, const RigidMotion* prior,
                               bool* background_fit);
  /// The geometric check of the matches against the camera motion (none in kDetector mode):
  /// is_dynamic has one flag per match. Records "epipolar".
  EpipolarResult flagMovingPoints(const MotionFilterInput& input, const FeatureMatches& m,
                                  const cv::Mat& depth_m, const std::vector<Detection>& dets,
                                  bool* background_fit);
  /// Fills what fusion may rely on in this frame besides the flags (and keeps the last depth).
  void gatherEvidence(const MotionFilterInput& input, const FeatureMatches& m,
                      const EpipolarResult& epi, FusionEvidence& evidence);
  /// Fusion of the flags and the detections, then the dense check. Records "fusion" and
  /// "dense_check".
  FusionResult fuseRegions(const MotionFilterInput& input, const FeatureMatches& m,
                           const cv::Mat& depth_m, const std::vector<Detection>& dets,
                           const EpipolarResult& epi, FusionEvidence& evidence);
  /// What the next frame needs of this one: its masks and (dense check) its depth and the pose
  /// it was checked with.
  void endFrame(const MotionFilterInput& input, const cv::Mat& depth_m, const FusionResult& fused);
  void keepDiagnostics(const FeatureMatches& m, const EpipolarResult& epi,
                       const MotionFilterOutput& out, std::vector<Detection> dets,
                       FusionResult fused);

  DynamicConfig config_;
  cv::Vec4d K_;  ///< fx, fy, cx, cy
  FusionMode mode_;
  ClassTable classes_;
  RegionFusion fusion_;
  std::unique_ptr<DetectorWorker> worker_;  ///< null when no detector is used
  struct LatestDetections {
    std::vector<Detection> detections;
    long frame_no = -1;  ///< frame number (beginFrame() count) they were computed on
    double stamp = 0.0;
  };
  LatestDetections latest_;
  long frame_no_ = -1;        ///< number of the frame given to the last beginFrame()
  double begun_stamp_ = 0.0;  ///< its timestamp
  TimingRecorder* timing_;
  TimingRecorder own_timing_;
  MotionDiagnostics diagnostics_;
  RigidMotion motion_;        ///< last frame-to-frame camera motion (diagnostics)
  cv::Mat prev_mask_;         ///< last frame's mask: its matches do not vote for the camera motion
  cv::Mat prev_kept_movers_;  ///< last frame's movers decided static (none is found there)
  std::vector<Detection> prev_people_;   ///< last frame's high-dynamic objects (no mover there)
  std::vector<Detection> prev_walkers_;  ///< ... those of them that were moving
  std::vector<Plane> planes_;            ///< this frame's support planes (camera frame)
  /// Recent frames with their final poses (DynamicConfig::dense_check_frames). The last frame
  /// waits in pending_ until the next filter() call brings its final pose.
  DepthHistory depth_history_;
  DepthView pending_;
  std::optional<cv::Matx44d> pending_prior_;  ///< the pose pending_'s frame was checked with
  long filtered_ = 0;  ///< filter() calls so far
};

/// nullptr for mode "off"; modes geometry | detector | both. Throws like the constructor.
std::unique_ptr<MotionFilter> makeMotionFilter(const DynamicConfig& config,
                                               const PinholeCamera& camera, TimingRecorder* timing);

/// Builds the detector options (kind, paths, input size, NMS) from the config.
DetectorOptions detectorOptions(const DynamicConfig& config);

/// Debug image: features green (static) / red (dynamic) with flow lines, boxes with class and
/// score (red = moving, yellow = static object), the mask as a red overlay.
cv::Mat drawMotionDebug(const cv::Mat& bgr, const MotionDiagnostics& diagnostics,
                        const ClassTable& classes);

/// One tab-separated line per decided object of the frame at `stamp_s` (class, score, box,
/// points, anchors, quiet frames, decision), to follow a person's decisions over time.
/// objectLogHeader() names the columns.
std::string objectLogLines(double stamp_s, const MotionDiagnostics& diagnostics,
                           const ClassTable& classes);
std::string objectLogHeader();

}  // namespace dynamap
