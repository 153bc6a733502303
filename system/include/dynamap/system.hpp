#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/core/frame.hpp"
#include "dynamap/core/motion_filter.hpp"
#include "dynamap/core/timing.hpp"
#include "dynamap/system/app_config.hpp"
#include "dynamap/system/trajectory.hpp"

namespace dynamap {

/// What System::track() returns for one frame.
struct TrackOutput {
  FrameStatus status = FrameStatus::kLost;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();  ///< camera -> world
  /// CV_8UC1, frame-sized, 255 = moving (all zeros when nothing moves or no filter runs).
  cv::Mat dynamic_mask;
  bool is_keyframe = false;
  KeyframePacketPtr keyframe;  ///< set iff is_keyframe (as the tracker made it)
  /// Keyframes handed to the mapper in this call, with the masks the map used: a keyframe waits
  /// mapping.mask_lookahead_frames frames for later masks (0: a keyframe is mapped at once and
  /// is its own entry here). See System::takeLastMapped() for the one finish() hands over.
  std::vector<KeyframePacketPtr> mapped;
};

/// Frame and keyframe counts so far.
struct SystemCounts {
  std::size_t frames = 0;  ///< frames given to track() / mapWithPose() / markBadFrame()
  std::size_t tracked = 0, relocalized = 0, lost = 0, bad_frames = 0;
  std::size_t posed_by_depth = 0;  ///< frames posed by their static depth alone (status "depth")
  std::size_t keyframes = 0;  ///< made and kept (not culled)
  /// Made, then culled as redundant (tracking.kf_cull_redundant): not in keyframes() or a saved
  /// map; their views stay in the dense map (mapped_keyframes counts them).
  std::size_t culled_keyframes = 0;
  /// Integrated by the backend so far: a keyframe is, about mapping.window_after_s after its
  /// frame (once judged); all of them after finish(). With mapping.visibility_final_pass the
  /// backend gets them only in finish() (0 before).
  std::size_t mapped_keyframes = 0;
  std::size_t map_elements = 0;  ///< the backend's points, voxels or cells so far

  std::size_t mapper_dropped = 0;  ///< SystemOptions::drop_keyframes_when_busy only
  /// From SystemOptions::load_map_dir: keyframes the run started with (`keyframes` counts only
  /// this run's new ones) and the saved dense map's points, voxels or cells (0 when the map was
  /// made with another backend: the run starts with the tracker's map only).
  std::size_t loaded_keyframes = 0;
  std::size_t loaded_map_elements = 0;
};

/// How a System is wired beyond the typed configuration.
struct SystemOptions {
  /// Folders searched for backend plugins before the defaults (the folders listed in the
  /// environment variable DYNAMAP_PLUGIN_PATH, <libdir>/dynamap and <libdir> of this library,
  /// and the build tree's lib/).
  std::vector<std::string> plugin_dirs;
  /// Replaces the motion filter built from config.dynamic (e.g. masks read from disk).
  std::unique_ptr<MotionFilter> motion_filter;
  /// Map from given poses with mapWithPose(): no tracker is built, track() throws.
  bool given_poses = false;
  /// A keyframe the busy mapper cannot take is dropped (counted) instead of waited for.
  bool drop_keyframes_when_busy = false;
  std::size_t mapping_queue_capacity = 16;
  /// The mapping thread's nice value (Linux; 0 = the process's). Nothing waits for the mapper
  /// while its queue has room, so with both cores busy it takes the gaps and leaves the tracker
  /// and detector theirs; what is left is drained beside the last bundle adjustment. Not applied
  /// with drop_keyframes_when_busy (a starved mapper would drop keyframes there).
  int mapping_thread_nice = 19;
  /// Start in the map that saveMap() wrote into this folder (empty = a new map): the tracker
  /// relocalizes in it within the first frames (lost until then), poses are in its frame and new
  /// keyframes extend it; the backend that made it starts from its dense map (MapBackend::
  /// importMap(): `points` / `pcl_voxel` its cloud, `vdb_tsdf` its grids, `octomap` its tree),
  /// another backend with the new keyframes only. A missing, corrupt or mismatched map (other
  /// camera, other format version, a volume of another voxel size) makes the constructor throw
  /// MapFileError naming the file and field. Not with given_poses.
  std::string load_map_dir;
  /// Where every stage records its timings (borrowed; must outlive the System). Null = the
  /// System keeps its own (timings()).
  TimingRecorder* timings = nullptr;
};

/// dynamap as a library: tracking with motion-area removal, keyframes, dense mapping into the
/// configured backend. `dynamap run` is a thin driver over this class.
///
/// Per frame, track() runs the tracker (features, dynamic regions, pose, keyframe decision),
/// hands a new keyframe to the mapping thread and forwards bundle-adjustment corrections.
/// The mapper judges and integrates each keyframe about a second after its frame, so
/// exportMapSnapshot() writes the map so far at any moment. finish() runs the final bundle
/// adjustment, gives the mapper the final keyframe poses and waits for it; exportMap() writes
/// the backend's files.
///
/// Threading: a System is not thread-safe. Call every method from one thread (or serialise
/// the calls); the bundle-adjustment, detector and mapping threads it owns are internal and
/// are joined by finish() or the destructor. Different System objects are independent.
/// Errors: the constructor and fromConfig() throw ConfigError for configuration problems
/// (message naming the file, line or key) and std::runtime_error for an unknown backend (the
/// message lists the known ones) or missing detector files; track() throws
/// std::invalid_argument for images of the wrong type or size. Tracking failures are values:
/// TrackOutput::status.
class System {
 public:
  explicit System(const AppConfig& config, SystemOptions options = {});
  /// The configuration `dynamap run` builds: code defaults, then the YAML file `config_path`
  /// (empty = none), then each "section.key=value" override. `effective_yaml`, when given,
  /// receives every key with its value.
  static std::unique_ptr<System> fromConfig(const std::string& config_path,
                                            const std::vector<std::string>& overrides,
                                            SystemOptions options = {},
                                            std::string* effective_yaml = nullptr);
  ~System();  ///< finish() if not done; joins every thread
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  /// A camera frame: `bgr` CV_8UC3; `depth` CV_16UC1 in units of camera.depth_scale per metre
  /// or CV_32FC1 in metres (0 = no reading), same size as `bgr`. Copied; undistorted when the
  /// camera has distortion. Throws std::invalid_argument on a wrong type or size.
  TrackOutput track(const cv::Mat& bgr, const cv::Mat& depth, double timestamp_s);
  /// A prepared frame (undistorted colour CV_8UC3, depth CV_32FC1 metres); not copied.
  TrackOutput track(const RgbdFrame& frame);
  /// A frame that could not be read: counted, no pose.
  void markBadFrame(double timestamp_s);
  /// The prepared frame that will be passed to track() next, as soon as it is read: the
  /// detector may start on it while the current frame is tracked (offline lockstep runs; the
  /// results are those without it). Optional. Thread-safe with track(); not after finish().
  void prefetch(const RgbdFrame& next);
  /// Given-pose mapping (SystemOptions::given_poses): every frame is a keyframe with pose
  /// `T_W_C` and dynamic mask `mask` (CV_8UC1 255 = moving, may be empty).
  TrackOutput mapWithPose(const RgbdFrame& frame, const Eigen::Isometry3d& T_W_C,
                          const cv::Mat& mask);

  /// Every tracked frame's pose: relative to its keyframe, recomposed with that keyframe's
  /// latest optimised pose (the final trajectory after finish()).
  std::vector<TimedPose> trajectory() const;
  std::vector<FrameStatus> frameStatuses() const;  ///< parallel to trajectory()
  std::vector<TimedPose> keyframes() const;        ///< latest optimised keyframe poses
  SystemCounts counts() const;

  /// Final bundle adjustment, final keyframe poses to the mapper, waits for mapping and stops
  /// the worker threads. Idempotent; track() throws std::logic_error afterwards.
  void finish();
  /// The keyframe finish() handed to the mapper (the one still waiting for later masks), once;
  /// empty if none. Thread-safe as finish().
  std::vector<KeyframePacketPtr> takeLastMapped();
  /// After finish(): keyframe id -> the mask the map used, for the keyframes whose masks
  /// finish() revised (held-back people another keyframe confirmed static; the packets keep
  /// the masks they had when mapped). Empty before finish().
  std::unordered_map<std::uint64_t, cv::Mat> revisedMasks() const;
  /// finish(), then writes the backend's map files into `dir` (created if needed).
  void exportMap(const std::string& dir);
  /// finish(), then writes what a later run needs into `dir` (created if needed; see
  /// SystemOptions::load_map_dir): `map.sqlite` (format version, camera, keyframes with poses
  /// and observations, landmarks with descriptors; dynamap/system/map_store.hpp) and the
  /// backend's files in `map/`. Throws MapFileError (or MappingError) on I/O failure; what was
  /// computed stays available (trajectory(), exportMap()). Not with given poses.
  void saveMap(const std::string& dir);
  /// The map as it is now, during the run, without finishing: waits until the mapper has taken
  /// the keyframes handed to it so far, then writes the backend's files into `dir` (created if
  /// needed). The keyframes of the last mapping.window_after_s are not in it yet. After
  /// finish(), the final map.
  void exportMapSnapshot(const std::string& dir);

  /// Per-stage timings of every thread so far (SystemOptions::timings when given).
  const TimingRecorder& timings() const;
  /// The motion filter in use (may be null: dynamic.mode=off or given poses).
  const MotionFilter* motionFilter() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dynamap
