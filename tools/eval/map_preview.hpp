#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dynamap/mapping/ply_io.hpp"  // PlyData
#include "trajectory_io.hpp"           // TimedPose

namespace dynamap {

/// A virtual camera looking at a map: pinhole (x right, y down, z forward) or orthographic.
/// Pixel of a camera-frame point p_C: perspective u = focal_px * x / z + cx;
/// orthographic u = focal_px * x + cx (focal_px is then pixels per metre).
struct PreviewCamera {
  std::string name;  ///< file suffix: "top", "oblique_1", ...
  Eigen::Isometry3f T_C_W = Eigen::Isometry3f::Identity();  ///< world -> camera
  Eigen::Vector3f up_W = Eigen::Vector3f::UnitZ();          ///< world up (height colours, labels)
  bool orthographic = false;
  float focal_px = 500.0f;
  float cx = 400.0f;
  float cy = 300.0f;
};

struct MapPreviewOptions {
  int width = 800;
  int height = 600;
  int splat_px = 3;                  ///< side of the square splat of one point
  std::size_t max_points = 1000000;  ///< larger maps are subsampled with a fixed stride
  float edl_strength = 40.0f;        ///< eye-dome lighting: darkening at depth steps
  float fog = 0.35f;                 ///< far surfaces are darkened by up to this fraction
  cv::Vec3b background{46, 40, 40};  ///< BGR
  bool labels = true;                ///< caption and (orthographic views) a scale bar
};

/// World up direction of a scene. With a camera trajectory: the direction normal to the image x
/// axes (horizontal for a hand-held camera without roll), or, when the camera never turned, the
/// mean image-up direction made normal to x; the sign follows the mean image-up direction.
/// Without a trajectory: the smallest principal axis of the map (a floor or table normal; tall
/// off-centre objects tilt it by a few degrees), largest component made positive.
Eigen::Vector3f estimateUp(const std::vector<Eigen::Vector3f>& points_W,
                           const std::vector<TimedPose>& trajectory);

/// Three cameras framing the map: "top" (orthographic, looking down the up axis, the map's
/// widest horizontal axis along the image x axis) and "oblique_1", "oblique_2" (perspective,
/// 35 degrees above the horizon, +-40 degrees around the side the cameras saw the scene from,
/// outside the bounding box). Each is zoomed to frame the 1st-99th percentile of the points.
/// Throws std::invalid_argument when `points_W` is empty.
std::vector<PreviewCamera> choosePreviewCameras(const std::vector<Eigen::Vector3f>& points_W,
                                                const std::vector<TimedPose>& trajectory,
                                                const MapPreviewOptions& options = {});

/// Renders the map seen by `camera`: z-buffered square splats of the vertices, or flat-shaded
/// triangles when the map has faces; vertex colours (or height colours when the map has none),
/// depth fog and eye-dome lighting so the shape reads. Returns a CV_8UC3 width x height image.
cv::Mat renderMapPreview(const PlyData& map, const PreviewCamera& camera,
                         const MapPreviewOptions& options = {});

/// choosePreviewCameras + renderMapPreview for each camera, written atomically as
/// out_dir/map_preview_<name>.png. Returns the file names (without folder), in camera order.
/// An empty map writes nothing. Throws std::runtime_error naming a file that cannot be written.
std::vector<std::string> writeMapPreviews(const PlyData& map,
                                          const std::vector<TimedPose>& trajectory,
                                          const std::string& out_dir,
                                          const MapPreviewOptions& options = {});

}  // namespace dynamap
