#pragma once

namespace dynamap {

/// Tracking front-end parameters. Defaults live here; dynamap::system binds them to YAML keys
/// "tracking.<name>" (system/src/config_bind_tracking.cpp).
struct TrackerConfig {
  // --- features (ORB over a scale pyramid, spread over a grid) ---
  int orb_features = 1000;         ///< ORB keypoints extracted per (key)frame before gridding
  int orb_levels = 8;              ///< ORB scale-pyramid levels
  double orb_scale_factor = 1.2;   ///< ORB scale between levels
  int orb_fast_threshold = 12;     ///< FAST threshold of the ORB detector
  int orb_fast_threshold_min = 5;  ///< FAST threshold filling cells ORB left empty (0 = off)
  int grid_cell_px = 32;           ///< spatial grid cell; the best keypoint per cell is kept
  int min_tracked_features = 100;  ///< fewer tracked features -> new keyframe + re-detection

  // --- Lucas-Kanade frame-to-frame matching ---
  /// Pyramid levels of Lucas-Kanade optical flow asked for. OpenCV builds only the levels larger
  /// than the window: at 640 x 480 with a 15 px window that is 5 (the 6th would be 20 x 15 px).
  int lk_levels = 6;
  double lk_scale = 0.5;            ///< scale between pyramid levels
  int lk_window_px = 15;            ///< LK window side
  int lk_max_iterations = 20;       ///< LK iterations per level
  double lk_fb_threshold_px = 1.0;  ///< forward-backward consistency threshold
  /// Pyramid levels of the backward (consistency) pass of the landmark tracks, which starts from
  /// the track's own position (0 = all that were built).
  int lk_backward_levels = 0;
  /// Threads LK splits a frame's points over (each point is tracked alone: same result with
  /// any number). 2 helps where a core is free; on 2 cores the detector already fills it.
  int lk_threads = 1;

  // --- motion probes (only with a motion filter) ---
  /// Extra LK points, not landmarks, appended to the matches handed to the motion filter so that
  /// it sees the whole image every frame (landmark tracks alone vanish from a mover once they
  /// are dropped, and a mover without tracks gets no mask). 0 = landmark tracks only.
  int motion_probes = 500;
  int motion_probe_min_distance_px = 12;  ///< spacing of probes (goodFeaturesToTrack)
  /// Pyramid levels of the probes' backward (consistency) pass, which starts from the probe's
  /// own position (0 = all that were built). Fewer levels pass more probes at the edges of
  /// movers and move the masks of people who stand (BENCHMARKS.md, session 45).
  int motion_probe_backward_levels = 0;

  /// With a motion filter: the camera motion handed to it is first estimated against the
  /// tracked landmarks that at least this many keyframes observed (those proven static over
  /// time), when there are enough of them (0 = no prior: the filter fits the motion itself).
  int static_prior_min_keyframes = 2;
  /// Features this close (px) to a motion region take no part in pose estimation nor become
  /// landmarks: an LK window half on a passing person is dragged along with it. The map's mask
  /// is not widened by it. 0 = the motion regions only.
  int dynamic_margin_px = 0;

  // --- depth ---
  double depth_min_m = 0.1;  ///< depth readings outside [min, max] are ignored
  double depth_max_m = 6.0;
  double landmark_depth_max_m = 4.5;  ///< new landmarks only from depth below this
  double depth_sigma_coeff = 0.006;   ///< depth std-dev model sigma_z = coeff * z^2 (metres)
  double pixel_sigma_px = 1.0;        ///< feature position std-dev

  // --- pose estimation ---
  int pnp_ransac_iterations = 100;
  double pnp_reprojection_px = 3.0;  ///< RANSAC inlier threshold
  int min_inliers = 15;              ///< fewer pose inliers -> frame is lost
  int refine_iterations = 10;        ///< Ceres iterations of the motion-only refinement
  double robust_loss_sigma = 2.8;    ///< Huber threshold on whitened residuals (sigma units)
  bool use_depth_residual = true;    ///< add a depth residual to the reprojection residual
  /// Constant-velocity prior of the motion-only refinement: std-dev of the camera centre (m)
  /// and rotation (deg) around the prediction (0 = off). Weak against hundreds of matches;
  /// it keeps the pose when walkers hide most of the scene for a few frames.
  double motion_prior_sigma_m = 0.01;
  double motion_prior_sigma_deg = 1.0;

  // --- keyframe policy: a keyframe when any of these holds ---
  double kf_min_tracked_ratio = 0.6;   ///< tracked / landmarks seen by the reference keyframe
  double kf_max_translation_m = 0.08;  ///< camera moved farther than this from the reference
  double kf_max_rotation_deg = 8.0;    ///< camera rotated more than this from the reference
  double kf_max_parallax_px = 40.0;    ///< median feature displacement since the reference
  double kf_max_interval_s = 1.0;      ///< time since the reference keyframe
  /// A frame whose dynamic mask, held-back objects left out (MotionFilterOutput::
  /// unconfirmed_mask), covers more than this share of the image makes no keyframe for lack of
  /// tracks (min_tracked_features, kf_min_tracked_ratio), only for the motion, time and parallax
  /// limits above (1 = always).
  double kf_max_masked_share = 0.35;
  /// ... unless fewer tracks than this are left (3 x min_inliers): the pose would be lost within
  /// frames (the Bonn slice: 13-23 tracks for 25 frames, then lost, then a restart), which
  /// costs more than landmarks near the movers (0 = off). Bonn slice, 6 starts each way: lost
  /// frames 7.7 / 5 -> 2.2 / 0, ATE 2.88 / 2.38 -> 1.99 / 1.68 cm; teddy's sequences unchanged.
  int kf_crowded_min_tracks = 45;
  /// Revisits: when a keyframe is due, the nearest keyframe within this share of the
  /// translation and rotation limits above becomes the reference again if the frame, with the
  /// landmarks of the keyframes near it found again, tracks kf_min_tracked_ratio x
  /// min_tracked_features points (kf_crowded_min_tracks in a frame beyond kf_max_masked_share;
  /// 2 x min_inliers after RANSAC), instead of a new keyframe with
  /// new landmarks beside the old ones: keyframes grow with the space explored, not with time
  /// (0 = off).
  double kf_reuse_distance = 0.5;
  /// ... unless more than this share of the frame's static view (outside its motion mask) lies
  /// outside the static views of the keyframes near it: a new keyframe adds that to the map
  /// (static scene the old ones had masked, or had not seen).
  double kf_reuse_max_uncovered_share = 0.05;
  /// ... and only keyframes at least this old (s): a revisit, after the camera went elsewhere.
  /// At 1.5 teddy x10 made 82 keyframes instead of ~96, but crowd x10 ran away in its last
  /// pass (54 keyframes, 1.05 -> 2.14 cm; at 5: 89 keyframes, 1.04 cm). The Bonn slice played
  /// back comes to pass 1's crowded frames 3.3-3.6 s later and makes new keyframes there. With
  /// ba_fixed_covisible 8, nine long runs (BENCHMARKS.md, session 64): at 5 / 4 / 3 s 512 / 496
  /// / 482 keyframes, 3 / 3 / 7 lost frames; at 4 two of six teddy_dyn_crowd_dev starts kept a
  /// walker (ghost 0.06 -> 3.6 %); 3 s without ba_fixed_covisible lost teddy_dyn_dev x10 in
  /// pass 6 (0.96 -> 2.08 cm). Alone (ba_covisible_min_age_s at 5 s; twelve long runs, session
  /// 66): at 3 s crowd x10 from frame 6 ran away (3.82 cm); at 2 s 703 keyframes for 736 and the
  /// crowd's mask IoU .775 for .754, but teddy_dyn_dev 0.86-0.89 -> 0.93-1.00 cm, 2 lost frames.
  double kf_reuse_min_age_s = 5.0;
  /// The revisited keyframes' landmarks are searched for among this many ORB keypoints of the
  /// frame, detected down to this FAST threshold: the top 1000 at 12 held a keypoint near only a
  /// third of the landmarks in view (teddy x10: 144 keyframes; 3000 at 7: 96).
  int kf_reuse_orb_features = 3000;
  int kf_reuse_orb_fast_threshold = 7;
  /// A keyframe made where the 8 nearest keyframes older than the bundle-adjustment window saw
  /// all but kf_reuse_max_uncovered_share of its static view, and their landmarks alone
  /// (2 x min_inliers inliers) pose the frame within 5 cm / 3 deg of its own tracks (1 cm /
  /// 0.5 deg with kf_cull_online), is culled when it leaves the window: it leaves the keyframe
  /// list and a saved map, follows the nearest of them rigidly (its frames keep their poses; its
  /// observations stay in bundle adjustment through that parent, its landmarks are searched as
  /// the parent's), and the dense map keeps what it held. Those still in the window at finish()
  /// are culled after the final bundle adjustment (their poses as it left them).
  bool kf_cull_redundant = true;
  /// Cull them during the run, when they leave the window (teddy x10: 96 -> 80 keyframes, one
  /// pass 64), instead of all at finish() after the final bundle adjustment (the same keyframes
  /// culled, every pose as without culling). Off: during the run it broke teddy x90 (10 minutes
  /// of camera) at pass 57 (a keyframe a frame, 14 lost frames at pass 74: 330 keyframes,
  /// 14.3 cm; without it 110 keyframes, 1.06 cm).
  bool kf_cull_online = false;

  // --- local bundle adjustment (own thread) ---
  bool bundle_adjustment = true;  ///< local BA on its own thread
  /// true: a BA result reaches the map when the next keyframe is made (the tracker waits for
  /// the solve in flight there), so an offline run repeats exactly; false: as soon as the BA
  /// thread finishes, whatever frame the tracker is on (`--realtime` sets false).
  bool ba_lockstep = true;
  int ba_window = 8;           ///< keyframes optimised together
  int ba_fixed_keyframes = 1;  ///< oldest keyframes of the window held fixed (gauge)
  /// Up to this many keyframes older than the window and ba_covisible_min_age_s older than its
  /// newest keyframe that see its landmarks (a revisit found them again) are held fixed in the
  /// local BA, so it keeps the old map's landmarks where the old keyframes put them. 0: only
  /// the window and the keyframes just before it (until session 64: nine long runs' mean ATE
  /// 1.34 cm, with 8 1.26 cm at the same kf_reuse_min_age_s; BENCHMARKS.md, "Long runs").
  int ba_fixed_covisible = 8;
  /// ... made at least this long (s) before the window's newest keyframe: an earlier visit's
  /// (until session 66 kf_reuse_min_age_s set both).
  double ba_covisible_min_age_s = 5.0;
  int ba_max_iterations = 10;
  /// Every this many keyframes the BA thread optimises every keyframe instead of the newest
  /// ba_window (stage "ba_global"), and the final BA only what came since (0 = never). Off:
  /// at 16, teddy x90 broke down after pass 78 (3.29 cm, 314 keyframes) and a map saved with it
  /// reloaded badly (teddy backward 12.1 cm, 96 new keyframes; 0.98 cm, 8 without it).
  int ba_global_every_keyframes = 0;
  /// The last bundle adjustment, at finish(), optimises the newest this many keyframes together,
  /// the oldest ba_fixed_keyframes of them held fixed. 0: those made since the last global BA
  /// and ba_window more (every keyframe when ba_global_every_keyframes is 0). The trajectory and
  /// the map take its poses; the masks and every online decision were made before it.
  int final_ba_window = 0;
  /// Its iterations: at 10 none of six runs (teddy, crowd, Bonn, each x1 and x10) converged, and
  /// 5 gave the same ATE (to 0.1 mm; Bonn x10 1.91 -> 1.82 cm) in half the time; 3 lost
  /// accuracy (Bonn x10 2.32 cm).
  int final_ba_max_iterations = 5;
  /// Keyframes made close in time (a view movers fill makes one every frame) hold few static
  /// points each, and bundle adjustment moves them apart (one-frame jumps of 1-2 cm on the Bonn
  /// slice): three keyframes in a row, each at most ba_acceleration_max_gap_s after the one
  /// before, get an acceleration prior on their camera centres (finite differences, in units of
  /// this sigma, m/s^2, Huber-weighted). A hand-held camera's accelerations stay within a few
  /// m/s^2 (the ground truths of teddy and the Bonn slice: at most 1.2 and 0.6 m/s^2 over
  /// 0.1 s); one-frame jitter of 5 mm is ~9 m/s^2 at 30 Hz. 0 = off. At 5 (6a9b451,
  /// docs/design.md): one-frame translation RPE on the Bonn slice 6.80 -> 5.82 mm forward,
  /// 6.86 -> 5.81 backward (12 starts each), ATE inside the noise of the means everywhere.
  double ba_acceleration_sigma_mps2 = 5.0;
  double ba_acceleration_max_gap_s = 0.25;
  /// The trajectory's frames take their reference keyframe's final pose; where the reference
  /// changes, the jump between the two keyframes' corrections is spread over the frames since
  /// the previous change (blendReferenceSwitches()), instead of each frame following its
  /// reference alone.
  bool blend_reference_switches = true;

  // --- search of the local map at keyframes ---
  /// Landmarks of the newest keyframes that are no longer tracked are matched by projection to
  /// a new keyframe's keypoints (and kept instead of new landmarks). 0 = off. 10 instead of 5
  /// (session 62; mean ATE over the six start frames of tests/real_data/bands.py): teddy 0.99 ->
  /// 0.90 cm, teddy_dyn_dev 0.91 -> 0.84, crowd 1.02 -> 0.96, crowd stride 2 0.83 -> 0.80, Bonn
  /// forward 2.04 -> 1.55 (worst start 3.46 -> 2.08), backward 1.59 -> 1.46; with the Bonn
  /// distortion set 2.10 -> 1.89 and 2.07 -> 1.79; Bonn x10 from frames 0 / 3 / 6: 1.65 / 3.08 /
  /// 1.96 -> 2.15 / 1.96 / 1.76; teddy x10 1.04 -> 0.84, crowd x10 1.16 -> 1.05. Mask IoU means
  /// -0.006 / +0.016 / -0.020 (teddy_dyn_dev / crowd / stride 2), every band held. 0.2 ms more
  /// per keyframe. A radius of 20 px instead (Bonn 2.72 / 2.45 cm) was worse.
  int local_search_keyframes = 10;
  double local_search_radius_px = 10.0;  ///< keypoint within this distance of the projection
  int local_search_max_hamming = 50;     ///< ORB descriptor distance gate
  /// Tracks run short (walkers cover the view; LK drops the points at their edges): while fewer
  /// than this many are left after the movers' tracks go, the landmarks of the keyframes near
  /// the predicted pose that no track follows are searched for among the frame's keypoints
  /// outside the movers, as revisits do (findMapLandmarks). The pose then keeps leaning on the
  /// map instead of on the landmarks that each crowded keyframe makes from its own pose, whose
  /// error they carry on from keyframe to keyframe (0 = off).
  int refind_below_tracks = 60;

  // --- relocalization ---
  /// The newest keyframes whose landmarks are matched, and up to as many of those nearest the
  /// last pose (within 4 keyframe spacings): on a revisit that reuses the map the keyframes in
  /// view are old (crowd x10 from frame 6, reuse age 3 s: lost 5 frames and a new map, 3.82 cm;
  /// with the near ones 0.94 cm).
  int reloc_keyframes = 30;
  int reloc_max_hamming = 64;  ///< ORB descriptor distance gate
  double reloc_ratio = 0.8;    ///< Lowe ratio test
  int reloc_min_inliers = 20;  ///< inliers needed to accept a relocalization
  /// ... or this many, when the pose lies within 10 cm and 10 deg of the last tracked one (a
  /// view the movers fill for a moment: the Bonn slice's relocalizations found 16-19); 0 = off.
  int reloc_near_last_min_inliers = 15;
  /// After this many frames lost in a row the map restarts where the camera was last seen
  /// (0 = never: stay lost until relocalization succeeds).
  int restart_after_lost_frames = 5;
  /// Where neither the features nor relocalization give the pose (a view filled by people),
  /// the depth of the frame's static pixels is aligned to the last tracked frame's
  /// (depth_alignment.hpp: OpenCV's ICP odometry); such frames make no keyframe and count as
  /// lost for the restart. On the Bonn slice it poses every frame that was lost (BENCHMARKS.md).
  bool depth_fallback = true;

  // --- loop closure (own thread; core/include/dynamap/core/tracking/loop_closer.hpp) ---
  /// Each keyframe's static ORB features (outside the widened motion mask and the held pixels,
  /// not on bad landmarks) go to a loop closer on its own thread: place recognition, geometric
  /// verification, an SE(3) pose graph. Its corrections move the keyframes, their landmarks,
  /// the current pose, and reach the mapping backends as pose updates. With ba_lockstep a
  /// correction found for keyframe k lands when keyframe k+1 is made (the tracker waits for the
  /// loop thread there), so an offline run repeats exactly; without it at the next frame.
  bool loop_closure = false;
};

}  // namespace dynamap
