#include "dynamap/system/app_config.hpp"

namespace dynamap {

void bindTrackingConfig(ConfigSchema& schema, TrackerConfig& c) {
  schema.addInt("tracking.orb_features", &c.orb_features, 50, 20000);
  schema.addInt("tracking.orb_levels", &c.orb_levels, 1, 16);
  schema.addDouble("tracking.orb_scale_factor", &c.orb_scale_factor, 1.01, 2.0);
  schema.addInt("tracking.orb_fast_threshold", &c.orb_fast_threshold, 1, 100);
  schema.addInt("tracking.orb_fast_threshold_min", &c.orb_fast_threshold_min, 0, 100);
  schema.addInt("tracking.grid_cell_px", &c.grid_cell_px, 4, 320);
  schema.addInt("tracking.min_tracked_features", &c.min_tracked_features, 10, 5000);

  schema.addInt("tracking.lk_levels", &c.lk_levels, 1, 10);
  schema.addDouble("tracking.lk_scale", &c.lk_scale, 0.5, 0.5);  // OpenCV's LK pyramid is fixed 0.5
  schema.addInt("tracking.lk_window_px", &c.lk_window_px, 5, 63);
  schema.addInt("tracking.lk_max_iterations", &c.lk_max_iterations, 1, 200);
  schema.addDouble("tracking.lk_fb_threshold_px", &c.lk_fb_threshold_px, 0.01, 20.0);
  schema.addInt("tracking.lk_backward_levels", &c.lk_backward_levels, 0, 10);
  schema.addInt("tracking.lk_threads", &c.lk_threads, 1, 2);
  schema.addInt("tracking.motion_probes", &c.motion_probes, 0, 10000);
  schema.addInt("tracking.motion_probe_min_distance_px", &c.motion_probe_min_distance_px, 1, 200);
  schema.addInt("tracking.motion_probe_backward_levels", &c.motion_probe_backward_levels, 0, 10);
  schema.addInt("tracking.static_prior_min_keyframes", &c.static_prior_min_keyframes, 0, 1000);
  schema.addInt("tracking.dynamic_margin_px", &c.dynamic_margin_px, 0, 200);
  schema.addDouble("tracking.motion_prior_sigma_m", &c.motion_prior_sigma_m, 0.0, 100.0);
  schema.addDouble("tracking.motion_prior_sigma_deg", &c.motion_prior_sigma_deg, 0.0, 180.0);

  schema.addDouble("tracking.depth_min_m", &c.depth_min_m, 0.0, 100.0);
  schema.addDouble("tracking.depth_max_m", &c.depth_max_m, 0.0, 100.0);
  schema.addDouble("tracking.landmark_depth_max_m", &c.landmark_depth_max_m, 0.1, 100.0);
  schema.addDouble("tracking.depth_sigma_coeff", &c.depth_sigma_coeff, 1e-5, 1.0);
  schema.addDouble("tracking.pixel_sigma_px", &c.pixel_sigma_px, 0.05, 20.0);

  schema.addInt("tracking.pnp_ransac_iterations", &c.pnp_ransac_iterations, 1, 10000);
  schema.addDouble("tracking.pnp_reprojection_px", &c.pnp_reprojection_px, 0.1, 50.0);
  schema.addInt("tracking.min_inliers", &c.min_inliers, 4, 1000);
  schema.addInt("tracking.refine_iterations", &c.refine_iterations, 0, 200);
  schema.addDouble("tracking.robust_loss_sigma", &c.robust_loss_sigma, 0.1, 100.0);
  schema.addBool("tracking.use_depth_residual", &c.use_depth_residual);

  schema.addDouble("tracking.kf_min_tracked_ratio", &c.kf_min_tracked_ratio, 0.0, 1.0);
  schema.addDouble("tracking.kf_max_translation_m", &c.kf_max_translation_m, 0.001, 100.0);
  schema.addDouble("tracking.kf_max_rotation_deg", &c.kf_max_rotation_deg, 0.1, 180.0);
  schema.addDouble("tracking.kf_max_parallax_px", &c.kf_max_parallax_px, 1.0, 1000.0);
  schema.addDouble("tracking.kf_max_interval_s", &c.kf_max_interval_s, 0.01, 1000.0);
  schema.addDouble("tracking.kf_max_masked_share", &c.kf_max_masked_share, 0.0, 1.0);
  schema.addInt("tracking.kf_crowded_min_tracks", &c.kf_crowded_min_tracks, 0, 100000);
  schema.addInt("tracking.refind_below_tracks", &c.refind_below_tracks, 0, 100000);
  schema.addDouble("tracking.kf_reuse_distance", &c.kf_reuse_distance, 0.0, 1.0);
  schema.addDouble("tracking.kf_reuse_max_uncovered_share", &c.kf_reuse_max_uncovered_share, 0.0,
                   1.0);
  schema.addDouble("tracking.kf_reuse_min_age_s", &c.kf_reuse_min_age_s, 0.0, 1e9);
  schema.addInt("tracking.kf_reuse_orb_features", &c.kf_reuse_orb_features, 1, 100000);
  schema.addInt("tracking.kf_reuse_orb_fast_threshold", &c.kf_reuse_orb_fast_threshold, 1, 255);
  schema.addBool("tracking.kf_cull_redundant", &c.kf_cull_redundant);
  schema.addBool("tracking.kf_cull_online", &c.kf_cull_online);

  schema.addBool("tracking.bundle_adjustment", &c.bundle_adjustment);
  schema.addBool("tracking.ba_lockstep", &c.ba_lockstep);
  schema.addInt("tracking.ba_window", &c.ba_window, 2, 100);
  schema.addInt("tracking.ba_fixed_keyframes", &c.ba_fixed_keyframes, 1, 99);
  schema.addInt("tracking.ba_fixed_covisible", &c.ba_fixed_covisible, 0, 1000);
  schema.addDouble("tracking.ba_covisible_min_age_s", &c.ba_covisible_min_age_s, 0.0, 1e9);
  schema.addInt("tracking.ba_max_iterations", &c.ba_max_iterations, 1, 500);
  schema.addInt("tracking.ba_global_every_keyframes", &c.ba_global_every_keyframes, 0, 1000000);
  schema.addInt("tracking.final_ba_window", &c.final_ba_window, 0, 1000000);
  schema.addInt("tracking.final_ba_max_iterations", &c.final_ba_max_iterations, 1, 500);
  schema.addDouble("tracking.ba_acceleration_sigma_mps2", &c.ba_acceleration_sigma_mps2, 0.0, 1e6);
  schema.addDouble("tracking.ba_acceleration_max_gap_s", &c.ba_acceleration_max_gap_s, 0.0, 1e3);
  schema.addBool("tracking.blend_reference_switches", &c.blend_reference_switches);

  schema.addInt("tracking.local_search_keyframes", &c.local_search_keyframes, 0, 1000);
  schema.addDouble("tracking.local_search_radius_px", &c.local_search_radius_px, 0.5, 200.0);
  schema.addInt("tracking.local_search_max_hamming", &c.local_search_max_hamming, 1, 256);

  schema.addInt("tracking.reloc_keyframes", &c.reloc_keyframes, 1, 10000);
  schema.addInt("tracking.reloc_max_hamming", &c.reloc_max_hamming, 1, 256);
  schema.addDouble("tracking.reloc_ratio", &c.reloc_ratio, 0.1, 1.0);
  schema.addInt("tracking.reloc_min_inliers", &c.reloc_min_inliers, 4, 1000);
  schema.addInt("tracking.reloc_near_last_min_inliers", &c.reloc_near_last_min_inliers, 0, 100000);
  schema.addInt("tracking.restart_after_lost_frames", &c.restart_after_lost_frames, 0, 1000000);
  schema.addBool("tracking.depth_fallback", &c.depth_fallback);
  schema.addBool("tracking.loop_closure", &c.loop_closure);
}

}  // namespace dynamap
