#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <cstdint>
#include <vector>

#include "dynamap/core/frame.hpp"
#include "dynamap/core/timing.hpp"
#include "dynamap/system/app_config.hpp"
#include "mask_eval.hpp"
#include "run_options.hpp"
#include "trajectory_io.hpp"
#include "tum_dataset.hpp"

namespace dynamap {

struct TrackOutput;

/// Frame counts of a run, written to run.json.
struct RunCounts {
  std::size_t frames_read = 0;
  std::size_t tracked = 0;
  std::size_t relocalized = 0;
  std::size_t posed_by_depth = 0;
  std::size_t lost = 0;
  std::size_t bad_frames = 0;
  std::size_t keyframes = 0;         ///< kept (SystemCounts::keyframes)
  std::size_t culled_keyframes = 0;  ///< made, then culled as redundant
  std::size_t mapped_keyframes = 0;
  std::size_t skipped_realtime = 0;  ///< --realtime: frames skipped because tracking lagged
  std::size_t mapper_dropped = 0;    ///< --realtime: keyframes the busy mapper did not take
  std::size_t loaded_keyframes = 0;  ///< --load-map: the saved map's (keyframes: this run's new)
  /// --load-map: the saved dense map's elements (0 when another backend saved it)
  std::size_t loaded_map_elements = 0;
};

/// What a run produced; filled even when it stops early.
struct RunResult {
  std::string status = "complete";  ///< complete | interrupted | failed
  std::string error;
  RunCounts counts;
  std::vector<TimedPose> trajectory;      ///< every frame with a pose, final optimised poses
  std::vector<std::string> frame_status;  ///< parallel to trajectory
  std::vector<TimedPose> keyframes;
  double wall_time_s = 0.0;  ///< the whole run: the frames, then finishing
  double finish_s = 0.0;     ///< finishing: last bundle adjustment, mapper queue, visibility pass
  /// CPU time of every thread over wall_time_s (user + system): steadier than the wall clock on
  /// a shared machine, and what 2 cores must fit into.
  double cpu_s = 0.0;
  std::string backend;
  std::string mode = "offline";  ///< offline | realtime
  std::string map_dir;
  /// Keyframe masks vs the sequence's ground-truth masks (DIR/mask/), when it has them: the
  /// masks the map used (after mapping.mask_lookahead_frames), and the tracker's own.
  MaskScoreSummary mask_scores;
  MaskScoreSummary tracker_mask_scores;
};

/// The run: frames -> tracking (with motion-area removal) -> keyframes -> mapping.
/// Owns every stage for the duration of one sequence. Not thread-safe; one run at a time.
class Pipeline {
 public:
  Pipeline(const RunOptions& options, const AppConfig& config, const TumSequence& sequence);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  /// Processes every frame (or until interrupted / a fatal error), then finalises: final
  /// poses, map export. Never throws: a failure is recorded in the result, and whatever was
  /// computed so far is still finalised.
  RunResult run();
  const TimingRecorder& timings() const { return timings_; }

 private:
  struct Stages;
  void processFrames(RunResult& result);
  void processFrame(std::size_t index, const FrameLoad& load, RunResult& result);
  void finalize(RunResult& result);
  /// Keeps (and with --save-masks writes) the masks of keyframes handed to the mapper.
  void mappedKeyframes(const std::vector<KeyframePacketPtr>& mapped);
  /// After finish(): the masks the mapper revised replace the ones kept and written.
  void revisedKeyframeMasks();
  /// After the timed run: the kept keyframe masks against the sequence's ground-truth masks
  /// (evaluation, not the system's work: it does not count in the run's time).
  void scoreKeyframeMasks(RunResult& result) const;
  void writeKeyframeMask(const SequenceEntry& entry, const cv::Mat& mask,
                         const cv::Size& size) const;
  void writeDebugImage(const SequenceEntry& entry, const RgbdFrame& frame,
                       const TrackOutput& tracked) const;
  /// --debug-images: every frame's object decisions, appended to OUT/debug/objects.tsv.
  void logObjects(const SequenceEntry& entry);

  RunOptions options_;
  AppConfig config_;
  const TumSequence& sequence_;
  TimingRecorder timings_;
  std::unique_ptr<Stages> stages_;
  std::string gt_masks_dir_;  ///< sequence_dir/mask when present
  bool object_log_started_ = false;
  std::unordered_map<std::uint64_t, std::size_t> keyframe_entry_;  ///< keyframe id -> entry
  std::map<std::uint64_t, std::size_t> mapped_entry_;              ///< mapped keyframe id -> entry
  /// With ground-truth masks: each keyframe's mask as the tracker made it (entry, mask), in
  /// keyframe order, and as the map used it (by keyframe id); kept PNG-encoded (a long run
  /// keeps one per keyframe: 300 KB raw, a few KB encoded).
  struct KeptMask {
    KeptMask() = default;
    KeptMask(std::size_t entry_index, const cv::Mat& mask);
    cv::Mat decoded() const;
    std::size_t entry = 0;
    std::vector<std::uint8_t> png;
  };
  std::vector<KeptMask> tracker_masks_;
  std::map<std::uint64_t, KeptMask> mapped_masks_;
};

}  // namespace dynamap
