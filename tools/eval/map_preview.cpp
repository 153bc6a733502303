// Software renderer of map previews (z-buffered splats / flat triangles + eye-dome lighting).
#include "map_preview.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "image_io.hpp"

namespace dynamap {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNear = 1e-3f;

struct Buffers {
  cv::Mat1f depth;  ///< camera z; +inf = background
  cv::Mat3b color;  ///< BGR before shading
};

struct Projected {
  float u = 0, v = 0, z = 0;
};

bool project(const PreviewCamera& cam, const Eigen::Vector3f& p_W, Projected* out) {
  const Eigen::Vector3f p = cam.T_C_W * p_W;
  if (cam.orthographic) {
    out->u = cam.focal_px * p.x() + cam.cx;
    out->v = cam.focal_px * p.y() + cam.cy;
  } else {
    if (p.z() < kNear) return false;
    out->u = cam.focal_px * p.x() / p.z() + cam.cx;
    out->v = cam.focal_px * p.y() / p.z() + cam.cy;
  }
  out->z = p.z();
  return std::isfinite(out->u) && std::isfinite(out->v);
}

/// BGR colour per vertex: the map's colours, else a colour map of the height along up.
std::vector<cv::Vec3b> vertexColors(const PlyData& map, const Eigen::Vector3f& up) {
  std::vector<cv::Vec3b> colors(map.vertices.size());
  if (map.colors.size() == map.vertices.size()) {
    for (std::size_t i = 0; i < colors.size(); ++i) {
      colors[i] = cv::Vec3b(map.colors[i][2], map.colors[i][1], map.colors[i][0]);
    }
    return colors;
  }
  std::vector<float> h(map.vertices.size());
  for (std::size_t i = 0; i < h.size(); ++i) h[i] = up.dot(map.vertices[i]);
  std::vector<float> sorted = h;
  std::sort(sorted.begin(), sorted.end());
  const float lo = sorted.empty() ? 0.0f : sorted[sorted.size() / 50];
  const float hi = sorted.empty() ? 1.0f : sorted[sorted.size() - 1 - sorted.size() / 50];
  cv::Mat1b ramp(1, 256);
  for (int i = 0; i < 256; ++i) ramp(0, i) = static_cast<std::uint8_t>(i);
  cv::Mat3b lut;
  cv::applyColorMap(ramp, lut, cv::COLORMAP_VIRIDIS);
  for (std::size_t i = 0; i < h.size(); ++i) {
    const float t = std::clamp((h[i] - lo) / std::max(hi - lo, 1e-6f), 0.0f, 1.0f);
    colors[i] = lut(0, static_cast<int>(t * 255.0f));
  }
  return colors;
}

void splatPoints(const PlyData& map, const std::vector<cv::Vec3b>& colors, const PreviewCamera& cam,
                 const MapPreviewOptions& options, Buffers* buf) {
  const std::size_t n = map.vertices.size();
  const std::size_t stride = std::max<std::size_t>(
      1, (n + options.max_points - 1) / std::max<std::size_t>(options.max_points, 1));
  const int s = std::max(1, options.splat_px);
  const float half = 0.5f * static_cast<float>(s - 1);
  const int w = buf->depth.cols, h = buf->depth.rows;
  Projected p;
  for (std::size_t i = 0; i < n; i += stride) {
    if (!project(cam, map.vertices[i], &p)) continue;
    const int u0 = static_cast<int>(std::floor(p.u - half));
    const int v0 = static_cast<int>(std::floor(p.v - half));
    if (u0 + s <= 0 || v0 + s <= 0 || u0 >= w || v0 >= h) continue;
    for (int v = std::max(v0, 0); v < std::min(v0 + s, h); ++v) {
      float* depth = buf->depth.ptr<float>(v);
      cv::Vec3b* color = buf->color.ptr<cv::Vec3b>(v);
      for (int u = std::max(u0, 0); u < std::min(u0 + s, w); ++u) {
        if (p.z < depth[u]) {
          depth[u] = p.z;
          color[u] = colors[i];
        }
      }
    }
  }
}

/// Flat colour of a triangle lit by a head light (|cos| of the normal to the viewing ray).
cv::Vec3b faceColor(const PlyData& map, const std::vector<cv::Vec3b>& colors,
                    const std::array<std::uint32_t, 3>& t, const PreviewCamera& cam) {
  const Eigen::Vector3f a = cam.T_C_W * map.vertices[t[0]];
  const Eigen::Vector3f b = cam.T_C_W * map.vertices[t[1]];
  const Eigen::Vector3f c = cam.T_C_W * map.vertices[t[2]];
  const Eigen::Vector3f n = (b - a).cross(c - a).normalized();
  const Eigen::Vector3f ray =
      cam.orthographic ? Eigen::Vector3f::UnitZ() : Eigen::Vector3f((a + b + c).normalized());
  const float light = 0.35f + 0.65f * std::abs(n.dot(ray));
  cv::Vec3b out;
  for (int ch = 0; ch < 3; ++ch) {
    const float mean = (colors[t[0]][ch] + colors[t[1]][ch] + colors[t[2]][ch]) / 3.0f;
    out[ch] = cv::saturate_cast<std::uint8_t>(mean * light);
  }
  return out;
}

void rasterTriangles(const PlyData& map, const std::vector<cv::Vec3b>& colors,
                     const PreviewCamera& cam, Buffers* buf) {
  const int w = buf->depth.cols, h = buf->depth.rows;
  const std::size_t nv = map.vertices.size();
  for (const auto& t : map.triangles) {
    if (t[0] >= nv || t[1] >= nv || t[2] >= nv) continue;
    Projected q[3];
    if (!project(cam, map.vertices[t[0]], &q[0]) || !project(cam, map.vertices[t[1]], &q[1]) ||
        !project(cam, map.vertices[t[2]], &q[2])) {
      continue;
    }
    const float area =
        (q[1].u - q[0].u) * (q[2].v - q[0].v) - (q[2].u - q[0].u) * (q[1].v - q[0].v);
    if (std::abs(area) < 1e-9f) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({q[0].u, q[1].u, q[2].u}))));
    const int x1 = std::min(w - 1, static_cast<int>(std::ceil(std::max({q[0].u, q[1].u, q[2].u}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({q[0].v, q[1].v, q[2].v}))));
    const int y1 = std::min(h - 1, static_cast<int>(std::ceil(std::max({q[0].v, q[1].v, q[2].v}))));
    if (x0 > x1 || y0 > y1) continue;
    const cv::Vec3b color = faceColor(map, colors, t, cam);
    const float inv_area = 1.0f / area;
    for (int y = y0; y <= y1; ++y) {
      float* depth = buf->depth.ptr<float>(y);
      cv::Vec3b* pixels = buf->color.ptr<cv::Vec3b>(y);
      const float py = static_cast<float>(y) + 0.5f;
      for (int x = x0; x <= x1; ++x) {
        const float px = static_cast<float>(x) + 0.5f;
        const float w0 = ((q[1].u - px) * (q[2].v - py) - (q[2].u - px) * (q[1].v - py)) * inv_area;
        const float w1 = ((q[2].u - px) * (q[0].v - py) - (q[0].u - px) * (q[2].v - py)) * inv_area;
        const float w2 = 1.0f - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const float z = cam.orthographic ? w0 * q[0].z + w1 * q[1].z + w2 * q[2].z
                                         : 1.0f / (w0 / q[0].z + w1 / q[1].z + w2 / q[2].z);
        if (z < depth[x]) {
          depth[x] = z;
          pixels[x] = color;
        }
      }
    }
  }
}

/// Depth fog and eye-dome lighting (darkening where neighbours are nearer), onto `out`.
void shade(const Buffers& buf, const MapPreviewOptions& options, cv::Mat3b* out) {
  std::vector<float> depths;
  for (int y = 0; y < buf.depth.rows; y += 2) {
    for (int x = 0; x < buf.depth.cols; x += 2) {
      if (std::isfinite(buf.depth(y, x))) depths.push_back(buf.depth(y, x));
    }
  }
  std::sort(depths.begin(), depths.end());
  const float z_lo = depths.empty() ? 0.0f : depths[depths.size() / 100];
  const float z_hi = depths.empty() ? 1.0f : depths[depths.size() - 1 - depths.size() / 100];
  cv::Mat1f log_depth(buf.depth.size());
  for (int y = 0; y < buf.depth.rows; ++y) {
    for (int x = 0; x < buf.depth.cols; ++x) {
      const float z = buf.depth(y, x);
      log_depth(y, x) = std::isfinite(z) ? std::log(std::max(z, kNear)) : kInf;
    }
  }
  constexpr int kRadius = 2;
  static const int kOffsets[8][2] = {{-1, 0},  {1, 0}, {0, -1}, {0, 1},
                                     {-1, -1}, {1, 1}, {-1, 1}, {1, -1}};
  const int w = buf.depth.cols, h = buf.depth.rows;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float ld = log_depth(y, x);
      if (!std::isfinite(ld)) continue;
      float response = 0.0f;
      for (const auto& o : kOffsets) {
        const int nx = x + kRadius * o[0], ny = y + kRadius * o[1];
        if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
        const float nd = log_depth(ny, nx);
        if (std::isfinite(nd)) response += std::max(0.0f, ld - nd);
      }
      const float t =
          std::clamp((buf.depth(y, x) - z_lo) / std::max(z_hi - z_lo, 1e-6f), 0.0f, 1.0f);
      const float light =
          std::exp(-options.edl_strength * response / 8.0f) * (1.0f - options.fog * t);
      const cv::Vec3b c = buf.color(y, x);
      (*out)(y, x) = cv::Vec3b(cv::saturate_cast<std::uint8_t>(c[0] * light),
                               cv::saturate_cast<std::uint8_t>(c[1] * light),
                               cv::saturate_cast<std::uint8_t>(c[2] * light));
    }
  }
}

/// Caption and, for orthographic views, a metric scale bar.
void drawLabels(const PreviewCamera& cam, const PlyData& map, cv::Mat3b* image) {
  const cv::Scalar ink(235, 235, 235);
  const std::string text =
      cam.name + " view, " +
      (map.triangles.empty() ? std::to_string(map.vertices.size()) + " points"
                             : std::to_string(map.triangles.size()) + " triangles");
  cv::putText(*image, text, {10, image->rows - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.5, ink, 1,
              cv::LINE_AA);
  if (!cam.orthographic || cam.focal_px <= 0) return;
  const double target_m = 0.2 * image->cols / cam.focal_px;
  double bar_m = 0.01;
  for (double candidate : {0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0}) {
    if (candidate <= target_m) bar_m = candidate;
  }
  const int bar_px = static_cast<int>(std::lround(bar_m * cam.focal_px));
  const int x1 = image->cols - 15, x0 = x1 - bar_px, y = image->rows - 18;
  cv::line(*image, {x0, y}, {x1, y}, ink, 2);
  cv::line(*image, {x0, y - 5}, {x0, y + 5}, ink, 1);
  cv::line(*image, {x1, y - 5}, {x1, y + 5}, ink, 1);
  char label[32];
  std::snprintf(label, sizeof(label), bar_m < 1.0 ? "%.0f cm" : "%.0f m",
                bar_m < 1.0 ? bar_m * 100.0 : bar_m);
  cv::putText(*image, label, {x0, y - 9}, cv::FONT_HERSHEY_SIMPLEX, 0.45, ink, 1, cv::LINE_AA);
}

}  // namespace

cv::Mat renderMapPreview(const PlyData& map, const PreviewCamera& camera,
                         const MapPreviewOptions& options) {
  Buffers buf;
  buf.depth = cv::Mat1f(options.height, options.width, kInf);
  buf.color = cv::Mat3b(options.height, options.width, options.background);
  const std::vector<cv::Vec3b> colors = vertexColors(map, camera.up_W);
  if (map.triangles.empty()) {
    splatPoints(map, colors, camera, options, &buf);
  } else {
    rasterTriangles(map, colors, camera, &buf);
  }
  cv::Mat3b image(options.height, options.width, options.background);
  shade(buf, options, &image);
  if (options.labels) drawLabels(camera, map, &image);
  return image;
}

std::vector<std::string> writeMapPreviews(const PlyData& map,
                                          const std::vector<TimedPose>& trajectory,
                                          const std::string& out_dir,
                                          const MapPreviewOptions& options) {
  std::vector<std::string> names;
  if (map.vertices.empty()) return names;
  for (const PreviewCamera& camera : choosePreviewCameras(map.vertices, trajectory, options)) {
    const std::string name = "map_preview_" + camera.name + ".png";
    writeImageAtomic((std::filesystem::path(out_dir) / name).string(),
                     renderMapPreview(map, camera, options));
    names.push_back(name);
  }
  return names;
}

}  // namespace dynamap
