#include "dynamap/system/app_config.hpp"

namespace dynamap {

void bindMappingConfig(ConfigSchema& schema, MappingConfig& c) {
  schema.addString("mapping.backend", &c.backend);
  schema.addStringMap("mapping.params", &c.params);
  StaticPointsOptions& s = c.static_points;
  schema.addDouble("mapping.depth_min_m", &s.depth_min_m, 0.0, 100.0);
  schema.addDouble("mapping.depth_max_m", &s.depth_max_m, 0.0, 100.0);
  schema.addInt("mapping.mask_dilation_px", &s.mask_dilation_px, 0, 100);
  schema.addInt("mapping.fused_mask_dilation_px", &s.fused_mask_dilation_px, 0, 100);
  schema.addDouble("mapping.depth_edge_threshold_m", &s.depth_edge_threshold_m, 0.0, 100.0);
  schema.addInt("mapping.stride", &s.stride, 1, 64);
  schema.addInt("mapping.mask_lookahead_frames", &c.mask_lookahead_frames, 0, 30);
  schema.addDouble("mapping.mask_margin_behind_m", &c.mask_margin_behind_m, 0.0, 10.0);
  schema.addBool("mapping.free_space_check", &s.free_space.enabled);
  schema.addInt("mapping.free_space_neighbours", &s.free_space.neighbours, 1, 20);
  schema.addDouble("mapping.free_space_margin_m", &s.free_space.margin_m, 0.0, 10.0);
  schema.addDouble("mapping.free_space_margin_per_m2", &s.free_space.margin_per_m2, 0.0, 10.0);
  schema.addInt("mapping.free_space_min_area_px", &s.free_space.min_area_px, 1, 1000000);
  schema.addInt("mapping.free_space_fringe_px", &s.free_space.fringe_px, 0, 100);
  VisibilityOptions& vis = s.visibility;
  schema.addBool("mapping.visibility_check", &vis.enabled);
  schema.addDouble("mapping.visibility_voxel_m", &vis.voxel_m, 0.005, 1.0);
  schema.addInt("mapping.visibility_min_views", &vis.min_views, 1, 1000);
  schema.addInt("mapping.visibility_downsample", &vis.downsample, 1, 16);
  schema.addDouble("mapping.visibility_margin_m", &vis.margin_m, 0.0, 10.0);
  schema.addDouble("mapping.visibility_margin_per_m2", &vis.margin_per_m2, 0.0, 10.0);
  schema.addInt("mapping.visibility_mask_min_views", &vis.mask_min_views, 0, 1000);
  schema.addDouble("mapping.visibility_mask_ratio", &vis.mask_ratio, 0.0, 1.0);
  schema.addDouble("mapping.visibility_mask_span_s", &vis.mask_span_s, 0.0, 1e6);
  schema.addDouble("mapping.visibility_mask_span_view_ratio", &vis.mask_span_view_ratio, 0.0, 1e6);
  schema.addInt("mapping.visibility_mask_near_px", &vis.mask_near_px, 0, 1000);
  schema.addDouble("mapping.visibility_mask_near_depth_m", &vis.mask_near_depth_m, 0.0, 100.0);
  schema.addInt("mapping.visibility_mask_near_max_views", &vis.mask_near_max_views, 1, 1000);
  schema.addInt("mapping.visibility_mask_near_object_max_views", &vis.mask_near_object_max_views, 0,
                1000);
  schema.addDouble("mapping.visibility_mask_near_object_view_ratio",
                   &vis.mask_near_object_view_ratio, 0.0, 1e6);
  schema.addInt("mapping.visibility_mask_grow_px", &vis.mask_grow_px, 0, 100);
  schema.addDouble("mapping.window_before_s", &s.window_before_s, 0.0, 1e6);
  schema.addDouble("mapping.window_after_s", &s.window_after_s, 0.0, 1e6);
  schema.addDouble("mapping.startup_s", &s.startup_s, 0.0, 1e6);
  schema.addDouble("mapping.startup_window_after_s", &s.startup_window_after_s, 0.0, 1e6);
  schema.addDouble("mapping.window_batch_s", &s.window_batch_s, 0.0, 1e6);
  schema.addInt("mapping.window_revisit_keyframes", &s.window_revisit_keyframes, 0, 1000);
  schema.addDouble("mapping.held_window_after_s", &s.held_window_after_s, 0.0, 1e6);
  schema.addBool("mapping.visibility_final_pass", &s.visibility_final_pass);
  schema.addDouble("mapping.held_revision_voxel_m", &s.held_revision_voxel_m, 0.0, 1.0);
  schema.addInt("mapping.held_revision_min_keyframes", &s.held_revision_min_keyframes, 1, 1000);
}

}  // namespace dynamap
