// libFuzzer target: the plugin-name lookup. Input: backend name on the first line, then
// "key=value" parameter lines. BackendRegistry::create must either throw MappingError or give
// a backend that takes one small keyframe.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dynamap/core/camera.hpp"
#include "dynamap/mapping/backend_registry.hpp"
#include "fuzz_util.hpp"

namespace {

const dynamap::BackendRegistry& registry() {
  static const dynamap::BackendRegistry r =
      dynamap::BackendRegistry::scan({DYNAMAP_FUZZ_PLUGIN_DIR});
  return r;
}

void integrateOne(dynamap::MapBackend& backend) {
  static const dynamap::PinholeCamera camera = [] {
    dynamap::PinholeCamera c;
    c.width = 8;
    c.height = 6;
    c.fx = c.fy = 5.0;
    c.cx = 3.5;
    c.cy = 2.5;
    return c;
  }();
  static const cv::Mat bgr(6, 8, CV_8UC3, cv::Scalar(10, 20, 30));
  static const cv::Mat depth(6, 8, CV_32FC1, cv::Scalar(1.0f));
  static const std::vector<Eigen::Vector3f> points = {{0.f, 0.f, 1.f}, {0.1f, 0.f, 1.f}};
  static const std::vector<std::array<std::uint8_t, 3>> colors = {{1, 2, 3}, {4, 5, 6}};
  dynamap::KeyframeView view;
  view.id = 1;
  view.camera = &camera;
  view.bgr = &bgr;
  view.static_depth_m = &depth;
  view.points_C = &points;
  view.colors = &colors;
  backend.integrate(view);
  (void)backend.stats();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::vector<std::string> lines = dynamap::fuzz::lines(text);
  dynamap::BackendParams params;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const auto eq = lines[i].find('=');
    if (eq == std::string::npos) continue;
    params[lines[i].substr(0, eq)] = lines[i].substr(eq + 1);
  }
  std::unique_ptr<dynamap::MapBackend> backend;
  try {
    backend = registry().create(lines[0], params);
  } catch (const dynamap::MappingError&) {
    return 0;
  }
  if (!backend) dynamap::fuzz::fail("create returned null without throwing");
  integrateOne(*backend);
  return 0;
}
