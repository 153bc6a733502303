#include "dynamap/system/app_config.hpp"

namespace dynamap {

void bindDynamicConfig(ConfigSchema& schema, DynamicConfig& c) {
  schema.addString("dynamic.mode", &c.mode, {"off", "geometry", "detector", "both"});
  schema.addDouble("dynamic.epipolar_threshold_px", &c.epipolar_threshold_px, 0.01, 100.0);
  schema.addInt("dynamic.min_matches", &c.min_matches, 8, 100000);
  schema.addDouble("dynamic.min_parallax_px", &c.min_parallax_px, 0.0, 1000.0);
  schema.addInt("dynamic.ransac_iterations", &c.ransac_iterations, 10, 100000);
  schema.addDouble("dynamic.ransac_confidence", &c.ransac_confidence, 0.5, 0.999999);
  schema.addDouble("dynamic.homography_inlier_ratio", &c.homography_inlier_ratio, 0.0, 10.0);

  schema.addString("dynamic.geometric_check", &c.geometric_check,
                   {"pnp_reprojection", "rigid", "epipolar"});
  schema.addDouble("dynamic.reprojection_threshold_px", &c.reprojection_threshold_px, 0.01, 100.0);
  schema.addDouble("dynamic.rigid_epipolar_threshold_px", &c.rigid_epipolar_threshold_px, 0.01,
                   100.0);
  schema.addInt("dynamic.bucket_px", &c.bucket_px, 1, 1000);
  schema.addDouble("dynamic.boxed_fit_weight", &c.boxed_fit_weight, 0.0, 1.0);
  schema.addDouble("dynamic.masked_fit_weight", &c.masked_fit_weight, 0.0, 1.0);
  schema.addString("dynamic.detector", &c.detector,
                   {"yolo_darknet", "yolov5_onnx", "yolov8_onnx", "nanodet_onnx", "none"});
  schema.addString("dynamic.model_cfg", &c.model_cfg);
  schema.addString("dynamic.model_weights", &c.model_weights);
  schema.addInt("dynamic.input_width", &c.input_width, 0, 4096);
  schema.addInt("dynamic.input_height", &c.input_height, 0, 4096);
  schema.addDouble("dynamic.score_threshold", &c.score_threshold, 0.0, 1.0);
  schema.addDouble("dynamic.high_dynamic_score_threshold", &c.high_dynamic_score_threshold, 0.0,
                   1.0);
  schema.addDouble("dynamic.nms_iou_threshold", &c.nms_iou_threshold, 0.0, 1.0);
  schema.addString("dynamic.nms", &c.nms, {"plain", "recall"});
  schema.addDouble("dynamic.soft_nms_sigma", &c.soft_nms_sigma, 0.01, 10.0);
  schema.addDouble("dynamic.nms_dedup_iou", &c.nms_dedup_iou, 0.0, 1.0);
  schema.addInt("dynamic.detector_threads", &c.detector_threads, 0, 256);
  schema.addBool("dynamic.detector_async", &c.detector_async);
  schema.addBool("dynamic.detector_lockstep", &c.detector_lockstep);
  schema.addInt("dynamic.detector_max_age_frames", &c.detector_max_age_frames, 0, 1000);
  schema.addInt("dynamic.detector_every_frames", &c.detector_every_frames, 1, 1000);
  schema.addDouble("dynamic.stale_box_growth_px", &c.stale_box_growth_px, 0.0, 100.0);

  schema.addStringList("dynamic.high_dynamic_classes", &c.high_dynamic_classes);
  schema.addDouble("dynamic.high_dynamic_weight", &c.high_dynamic_weight, 0.0, 1.0);
  schema.addDouble("dynamic.low_dynamic_weight", &c.low_dynamic_weight, 0.0, 1.0);
  schema.addStringMap("dynamic.class_weights", &c.class_weights);

  schema.addDouble("dynamic.moving_ratio", &c.moving_ratio, 0.0, 1.0);
  schema.addInt("dynamic.min_object_points", &c.min_object_points, 1, 100000);
  schema.addInt("dynamic.min_dynamic_points", &c.min_dynamic_points, 1, 100000);
  schema.addDouble("dynamic.evidence_smoothing", &c.evidence_smoothing, 0.0, 0.99);
  schema.addInt("dynamic.static_confirm_frames", &c.static_confirm_frames, 0, 100000);
  schema.addDouble("dynamic.static_max_dynamic_share", &c.static_max_dynamic_share, 0.0, 1.0);
  schema.addDouble("dynamic.static_max_drift_m", &c.static_max_drift_m, 0.0, 100.0);
  schema.addDouble("dynamic.static_anchor_px", &c.static_anchor_px, 0.0, 1000.0);
  schema.addDouble("dynamic.static_anchor_m", &c.static_anchor_m, 0.0, 1.0);
  schema.addDouble("dynamic.static_anchor_depth_m", &c.static_anchor_depth_m, 0.001, 10.0);
  schema.addDouble("dynamic.static_surface_m", &c.static_surface_m, 0.0, 1.0);
  schema.addInt("dynamic.static_anchor_move_frames", &c.static_anchor_move_frames, 1, 2);
  schema.addInt("dynamic.dense_check_frames", &c.dense_check_frames, 0, 120);
  schema.addInt("dynamic.dense_min_region_px", &c.dense_min_region_px, 1, 1000000);
  schema.addDouble("dynamic.dense_depth_range_m", &c.dense_depth_range_m, 0.001, 10.0);
  schema.addDouble("dynamic.dense_grow_m", &c.dense_grow_m, 0.0, 10.0);
  schema.addDouble("dynamic.dense_barrier_step_m", &c.dense_barrier_step_m, 0.0, 10.0);
  schema.addBool("dynamic.views_follow_pose_snaps", &c.views_follow_pose_snaps);
  schema.addBool("dynamic.mover_tracks", &c.mover_tracks);
  schema.addBool("dynamic.hold_moved_objects", &c.hold_moved_objects);
  schema.addBool("dynamic.mover_follow_anchors", &c.mover_follow_anchors);
  schema.addInt("dynamic.mover_view_frames", &c.mover_view_frames, 0, 120);
  schema.addDouble("dynamic.mover_max_depth_m", &c.mover_max_depth_m, 0.0, 100.0);
  schema.addInt("dynamic.track_max_missed_frames", &c.track_max_missed_frames, 0, 100000);
  schema.addInt("dynamic.remember_still_frames", &c.remember_still_frames, 0, 1000000);
  schema.addBool("dynamic.carried_border_exit", &c.carried_border_exit);
  schema.addDouble("dynamic.depth_band_m", &c.depth_band_m, 0.01, 10.0);
  schema.addDouble("dynamic.person_max_height_m", &c.person_max_height_m, 0.0, 10.0);
  schema.addInt("dynamic.support_planes", &c.support_planes, 0, 10);
  schema.addInt("dynamic.mask_dilation_px", &c.mask_dilation_px, 0, 100);
  schema.addDouble("dynamic.static_carve_radius_px", &c.static_carve_radius_px, 0.0, 1000.0);
  schema.addDouble("dynamic.cluster_radius_px", &c.cluster_radius_px, 1.0, 1000.0);
  schema.addInt("dynamic.min_cluster_points", &c.min_cluster_points, 1, 100000);
  schema.addDouble("dynamic.cluster_max_consistent", &c.cluster_max_consistent, 0.0, 1.0);
  schema.addDouble("dynamic.cluster_max_depth_m", &c.cluster_max_depth_m, 0.0, 100.0);
  schema.addDouble("dynamic.flood_depth_step_m", &c.flood_depth_step_m, 0.001, 10.0);
  schema.addDouble("dynamic.cluster_box_margin", &c.cluster_box_margin, 1.0, 10.0);
}

}  // namespace dynamap
