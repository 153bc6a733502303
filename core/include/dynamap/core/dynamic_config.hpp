#pragma once

#include <map>
#include <string>
#include <vector>

namespace dynamap {

/// Motion-area removal parameters, bound to YAML keys "dynamic.<name>"
/// (system/src/config_bind_dynamic.cpp).
///
/// Model paths: an absolute path is used as is. A relative path is resolved by
/// resolveDynamicModelPaths(): first against the current working directory, then against the
/// parent of the config file's directory (so "../shared/models/..." in config/default.yaml means
/// <repo>/../shared/models/...). The factory checks every path and throws naming the file.
struct DynamicConfig {
  std::string mode = "both";           ///< off | geometry | detector | both
  double epipolar_threshold_px = 1.0;  ///< matches farther from their epipolar line are dynamic

  // --- geometric check -------------------------------------------------------------------
  int min_matches = 30;          ///< fewer matches: flag nothing (degenerate)
  double min_parallax_px = 0.3;  ///< median flow below this: flag nothing (no information)
  double ransac_confidence = 0.999;
  int ransac_iterations = 200;  ///< rigid check: at most this many minimal samples
  /// Homography explains >= this share of the F inliers: low parallax / pure rotation; the
  /// homography transfer error is used instead of the ill-conditioned epipolar distance.
  double homography_inlier_ratio = 0.85;
  /// pnp_reprojection (default; "rigid" is its older name): the camera motion by PnP with the
  /// current depth, each match's reprojection error against reprojection_threshold_px (3 px;
  /// matches without depth: epipolar distance to that motion's F); epipolar: the paper's check,
  /// RANSAC fundamental matrix and distance to the epipolar line (epipolar_threshold_px, 1 px).
  std::string geometric_check = "pnp_reprojection";
  double reprojection_threshold_px = 3.0;  // scene residuals ~0.5 px; slow walkers ~4 px
  /// rigid check, matches without depth: symmetric epipolar distance to the PnP pose's F
  double rigid_epipolar_threshold_px = 2.5;
  int bucket_px = 40;               ///< model fits use at most 2 matches per bucket_px cell
  double boxed_fit_weight = 0.2;    ///< vote of a match inside a high-dynamic box (rigid fit)
  double masked_fit_weight = 0.05;  ///< vote of a match inside last frame's mask (rigid fit)

  // --- detector -----------------------------------------------------------------------------
  std::string detector = "yolo_darknet";  ///< yolo_darknet | yolov5_onnx | yolov8_onnx |
                                          ///< nanodet_onnx | none
  std::string model_cfg = "../shared/models/yolo-fastest/yolo-fastest-1.1-xl.cfg";
  std::string model_weights = "../shared/models/yolo-fastest/yolo-fastest-1.1-xl.weights";
  int input_width = 0;            ///< detector input; 0 = the detector's default (defaultInputSize)
  int input_height = 0;           ///< detector input; 0 = the detector's default (defaultInputSize)
  double score_threshold = 0.25;  ///< low-dynamic classes
  double high_dynamic_score_threshold = 0.15;  ///< high-dynamic classes (recall first)
  double nms_iou_threshold = 0.45;
  std::string nms = "recall";   ///< plain (class-wise hard NMS) | recall (class-aware soft-NMS)
  double soft_nms_sigma = 0.5;  ///< Gaussian soft-NMS: score *= exp(-iou^2 / sigma)
  /// Recall NMS: meant to drop duplicates above this IoU after soft-NMS, but not applied:
  /// nms.cpp has no such pass (the option came in c52fd65 without one).
  double nms_dedup_iou = 0.7;
  /// >0: cv::setNumThreads on first detection (process-wide: OpenCV's pool is global). 1 by
  /// default: on a 2-core machine the detector, tracker, BA and mapper threads already fill both
  /// cores, and a second OpenCV worker per call only adds contention.
  int detector_threads = 1;
  /// true: beginFrame() hands the frame to the detector thread only when it is idle (other
  /// frames are skipped, counted as "detector_skipped") and filter() never waits: it uses the
  /// newest finished detections, their boxes grown by stale_box_growth_px per frame of age.
  /// false: every frame is detected and filter() waits for its own detections.
  bool detector_async = true;
  /// With detector_async: true = frame i always uses the detections of frame i-1 (beginFrame()
  /// waits for them, then hands frame i over), so an offline run repeats exactly and the
  /// detector still overlaps tracking; false = the newest finished detections, frames arriving
  /// while the detector is busy are skipped (`--realtime` sets false).
  bool detector_lockstep = true;
  int detector_max_age_frames = 6;  ///< older detections are not used (async)
  /// Lockstep runs: only every Nth frame goes to the detector (the first always); the frames
  /// between use the newest detections, their boxes moved by the flow inside them and grown
  /// by stale_box_growth_px per frame of age. 1 = every frame.
  int detector_every_frames = 1;
  double stale_box_growth_px = 3.0;  ///< per frame of age, on every side (async)

  // --- class table --------------------------------------------------------------------------
  /// COCO names of high-dynamic classes (can move by themselves).
  std::vector<std::string> high_dynamic_classes{
      "person",   "bicycle", "car",   "motorcycle", "bus",     "train", "truck",
      "boat",     "bird",    "cat",   "dog",        "horse",   "sheep", "cow",
      "elephant", "bear",    "zebra", "giraffe",    "airplane"};
  double high_dynamic_weight = 1.0;  ///< default prior of a high-dynamic class
  double low_dynamic_weight = 0.3;   ///< default prior of every other class
  /// Per-class prior overrides, "dynamic.class_weights.<coco name>: w" (0 = never masked).
  std::map<std::string, std::string> class_weights{{"person", "1.0"}, {"chair", "0.5"}};

  // --- fusion -------------------------------------------------------------------------------
  double moving_ratio = 0.7;        ///< weighted share of dynamic points to call an object moving
  int min_object_points = 4;        ///< tracked points needed inside an object to decide
  int min_dynamic_points = 3;       ///< dynamic points needed inside an object to call it moving
  double evidence_smoothing = 0.6;  ///< weight of the past in the per-object motion evidence
  /// A high-dynamic object (person) is masked until this many observed frames showed it still
  /// against a background-only camera motion (0 = kept unless it moves in this frame).
  int static_confirm_frames = 5;
  /// An observed frame counts as static evidence when at most this share of the object's points
  /// is dynamic (a near object's edges and occlusions flag a few points of a still one).
  double static_max_dynamic_share = 0.25;
  /// ... and while its world position (centroid of its pixels, camera pose from landmarks proven
  /// static) stays within this of where the quiet run began (m; 0 = not checked).
  double static_max_drift_m = 0.15;
  /// ... and, where at least 3 of its tracked points were anchored in the world in earlier
  /// frames, while their median reprojection distance stays within this (px; 0 = not checked).
  /// This replaces the centroid test where it applies: a person swaying 5 cm on the spot moves
  /// its points by several pixels, while its centroid wanders that much with occlusion alone.
  double static_anchor_px = 3.0;
  /// ... or, if larger, this distance (m) seen at the object's depth: a person standing still
  /// sways a centimetre or so (0 = pixels only).
  double static_anchor_m = 0.015;
  /// ... and their signed median depth difference within this (m): a sway along the line of
  /// sight. Twice either threshold is motion: the count of quiet frames starts over.
  double static_anchor_depth_m = 0.03;
  /// ... and the signed median depth change of its whole surface since kSurfaceBaselineFrames
  /// (12) frames back (its pixels sampled then, seen now: hundreds of depths) within this (m;
  /// 0 = not checked); twice it is motion. A person swaying a few centimetres along the line of
  /// sight 3 m away moves a dozen edge features within their depth noise, but the median of his
  /// surface beyond it; a still one keeps it within a few millimetres. It only adds motion: alone
  /// (too few anchored points) it calls nothing still.
  double static_surface_m = 0.015;
  /// For a person already confirmed still: frames in a row his anchors must be off by twice the
  /// limit before the count starts over (1 = the first one). Masked (held) in those frames.
  int static_anchor_move_frames = 2;
  /// Dense check without a detector: the depth of the frame this many frames back (0 = off),
  /// seen from the current pose, against the current depth. Pixels it saw through (beyond
  /// the sensor noise), outside the detected objects, in groups of at least dense_min_region_px,
  /// are grown into their surface (pixels within dense_depth_range_m of their depth, inside
  /// their box grown by dense_grow_m on each side) and masked: a pushed box, an arm, a person
  /// before the detector finds them.
  int dense_check_frames = 6;
  int dense_min_region_px = 800;
  double dense_depth_range_m = 0.15;
  double dense_grow_m = 0.5;
  /// Growth stops at a step in depth between neighbouring pixels larger than this plus 1 % of
  /// the depth (m; 0 = only the fixed range bounds it): a mover next to a static object at its
  /// depth does not take it.
  double dense_barrier_step_m = 0.0;
  /// A frame whose final pose jumped from the pose it was checked with by more than 1 deg or
  /// 1 cm (drift corrected at once, e.g. by landmarks found again) moves the earlier views kept
  /// for the dense check and the movers with it (DepthHistory::followPoseSnap()): later frames
  /// are not compared with views across the jump. Crowd x10: a frame 2 deg off before such a
  /// jump saw 40 k pixels of floor "through" and masked them in a keyframe (IoU .50 -> .71);
  /// Bonn x10 1.065 -> 1.043 cm; mover scenes and 36 people runs the same but one (-.001).
  bool views_follow_pose_snaps = true;
  /// The dense check's regions become class-less objects ("mover", ClassTable::kMover) that
  /// fusion tracks as it tracks people (needs mode both): a pushed box stays masked between the
  /// frames the check finds it in, and is kept once it has stood still for static_confirm_frames
  /// (false: each frame's regions are masked in that frame only). 8 generated mover scenes
  /// (BENCHMARKS.md, issue 50), with mover_view_frames 12: mean ATE 3.81 -> 1.02 cm, keyframe
  /// mask IoU .49 -> .69; the people sequences within their noise.
  bool mover_tracks = true;
  /// Movers are found against the depth this many frames back (0 = dense_check_frames). 12
  /// finds far more of a pushed chair or box (BENCHMARKS.md).
  int mover_view_frames = 12;
  /// Movers are sought only in current depth up to this range (m; 0 = any): beyond the range
  /// the map takes (mapping.depth_max_m, 4 m) a structured-light sensor's depth
  /// bends by tens of centimetres towards the image corners, and a far wall seen again from
  /// another place looked "seen through" (crowd x10: every backward pass, at 4-5.2 m).
  double mover_max_depth_m = 4.0;
  /// An object of another class (a chair) that was seen to move (its flags, or its anchors off
  /// by twice the still limit) is masked until it has stood still for static_confirm_frames, as
  /// a person is (false: only while its smoothed flags say it moves). A chair pushed away from
  /// the camera flags few points in most frames, while its anchors drift frame after frame.
  /// Under a person's box nothing starts a hold (a walker passing in front of a chair).
  bool hold_moved_objects = true;
  /// A mover the depth check no longer finds is followed (carried by the flow) for as long as
  /// its own points keep moving off their world anchors, not only track_max_missed_frames: a box
  /// pushed straight away from the camera is never seen through.
  bool mover_follow_anchors = false;
  /// An object the detector misses keeps its track (and, if moving, its mask) this many frames.
  int track_max_missed_frames = 8;
  /// A person (or a teddy taken for one) confirmed still whose track ends (hidden behind walkers
  /// longer than track_max_missed_frames) is remembered this many frames: detected again with
  /// its own anchored points, still where they were, it is kept at once instead of being held
  /// until it proves still again (crowd x10: the teddy masked in four keyframes). 0 = off.
  int remember_still_frames = 300;
  /// Such a carried box at the image border whose centre shows depth, but none within 0.5 m of
  /// its object's last depth, has lost the object through the border: it masks nothing (false:
  /// it takes the centre's dominant depth, e.g. the wall behind a person who walked out).
  bool carried_border_exit = true;
  double depth_band_m = 0.4;  ///< object pixels: within this of the object's depth mode
  /// A person's pixels lie no farther than where its box (h pixels tall) would be this tall
  /// (m; detector boxes are loose): beyond, the box shows what is behind the person (the wall
  /// beside a walker cut by the border, a carried box left on the wall). 0 = no bound.
  double person_max_height_m = 2.5;
  /// Up to this many large planes (floor, walls; found outside the objects each frame) are no
  /// object's pixels: the floor at a walker's feet, a box carried by the flow onto the floor.
  /// 0 = off.
  int support_planes = 3;
  int mask_dilation_px = 3;  ///< final dilation of each region (mapping dilates again)
  /// A moving object's pixels nearer (by more than 4 px) to a static tracked point inside it than
  /// to any dynamic one, and within this radius of it, are not masked: a standing person next to
  /// a walker at the same depth falls into the walker's depth cut. 0 = off.
  double static_carve_radius_px = 24.0;
  double cluster_radius_px = 40;  ///< dynamic points closer than this form one cluster
  int min_cluster_points = 4;     ///< smaller clusters outside detections are noise
  /// A cluster's grown region that the dense check's earlier view (dense_check_frames back, seen
  /// from the current pose) saw in place, at least this share of its depth samples agreeing, is
  /// a still surface under false flags (tracks dragged beside a walker, a far poster), not a
  /// mover: it is not masked. 0 = off (also without dense_check_frames).
  double cluster_max_consistent = 0.9;
  /// A cluster whose flagged points lie mostly beyond this depth (m; 0 = any) is not grown nor
  /// masked: that far a structured-light sensor's depth bends and jumps by tens of centimetres
  /// from view to view, the check above sees it "seen through", and the map (4 m) takes none of
  /// it (crowd played backward: a wall at 6-7 m behind an open door, 13 k pixels masked in a
  /// keyframe). Not the movers' 4 m: the flood from a walker's points at 4-4.5 m reaches his
  /// nearer legs, which the map takes (crowd x10 with 4: keyframe-mask IoU .766 -> .717, ghost
  /// .03 -> .29 %). BENCHMARKS.md, "Long runs".
  double cluster_max_depth_m = 5.0;
  double flood_depth_step_m = 0.03;  ///< depth continuity of the flood fill from clusters
  double cluster_box_margin = 1.5;   ///< flood fill stays inside cluster box grown by this
};

/// Resolves relative model paths (see DynamicConfig): CWD first, then the parent of the
/// directory of `config_file` (if given). Paths that exist nowhere are left unchanged, so
/// that the factory's error names them.
void resolveDynamicModelPaths(DynamicConfig& config, const std::string& config_file);

}  // namespace dynamap
