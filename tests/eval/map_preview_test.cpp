#include <chrono>
#include <cmath>
#include <filesystem>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "map_preview.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

constexpr int kW = 400, kH = 300;

MapPreviewOptions testOptions() {
  MapPreviewOptions o;
  o.width = kW;
  o.height = kH;
  o.labels = false;
  return o;
}

/// Camera at world (0, 0, -distance) looking along +z (camera frame = world frame shifted).
PreviewCamera frontCamera(float distance, float focal) {
  PreviewCamera cam;
  cam.name = "front";
  cam.T_C_W = Eigen::Isometry3f::Identity();
  cam.T_C_W.translation() = Eigen::Vector3f(0, 0, distance);
  cam.up_W = -Eigen::Vector3f::UnitY();
  cam.focal_px = focal;
  cam.cx = kW / 2.0f;
  cam.cy = kH / 2.0f;
  return cam;
}

/// Surface points of the cube [-1, 1]^3, 21 x 21 per face, each face its own colour.
PlyData colouredCube() {
  PlyData cube;
  const std::array<std::uint8_t, 3> colours[6] = {{255, 0, 0},   {0, 255, 0},   {0, 0, 255},
                                                  {255, 255, 0}, {0, 255, 255}, {255, 0, 255}};
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      for (int i = 0; i <= 20; ++i) {
        for (int j = 0; j <= 20; ++j) {
          Eigen::Vector3f p;
          p[axis] = side == 0 ? -1.0f : 1.0f;
          p[(axis + 1) % 3] = -1.0f + 0.1f * i;
          p[(axis + 2) % 3] = -1.0f + 0.1f * j;
          cube.vertices.push_back(p);
          cube.colors.push_back(colours[2 * axis + side]);
        }
      }
    }
  }
  return cube;
}

bool isBackground(const cv::Vec3b& c, const MapPreviewOptions& o) { return c == o.background; }

TEST(MapPreview, CubeCoversItsProjectedSquareAndNothingElse) {
  const MapPreviewOptions options = testOptions();
  const PreviewCamera cam = frontCamera(5.0f, 200.0f);
  const cv::Mat3b image = renderMapPreview(colouredCube(), cam, options);
  ASSERT_EQ(image.cols, kW);
  ASSERT_EQ(image.rows, kH);
  // The near face (z = -1, camera depth 4) spans +-200/4 = 50 px around the centre; the far
  // face (depth 6) lies inside it. Allow the 3 px splat (+2 px).
  int inside = 0, outside = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const bool in_square = std::abs(x + 0.5f - cam.cx) <= 52 && std::abs(y + 0.5f - cam.cy) <= 52;
      if (isBackground(image(y, x), options)) continue;
      (in_square ? inside : outside)++;
    }
  }
  EXPECT_EQ(outside, 0);
  EXPECT_GT(inside, 0.8 * 100 * 100);  // the square is nearly covered (points every 5 px)
  // The centre shows the near face z = -1 (cyan), hiding the far face z = +1 (magenta).
  const cv::Vec3b centre = image(kH / 2, kW / 2);
  EXPECT_GT(centre[0], 60);  // blue channel of cyan (BGR)
  EXPECT_GT(centre[1], 60);  // green
  EXPECT_LT(centre[2], 30);  // no red: the far magenta face is hidden
}

TEST(MapPreview, NearRedPointHidesFarBluePointWhateverTheOrder) {
  const MapPreviewOptions options = testOptions();
  const PreviewCamera cam = frontCamera(0.0f, 200.0f);
  for (int order = 0; order < 2; ++order) {
    PlyData map;
    const Eigen::Vector3f near_p(0, 0, 2), far_p(0, 0, 4);
    const std::array<std::uint8_t, 3> red{255, 0, 0}, blue{0, 0, 255};
    map.vertices = order == 0 ? std::vector<Eigen::Vector3f>{near_p, far_p}
                              : std::vector<Eigen::Vector3f>{far_p, near_p};
    map.colors = order == 0 ? std::vector<std::array<std::uint8_t, 3>>{red, blue}
                            : std::vector<std::array<std::uint8_t, 3>>{blue, red};
    const cv::Mat3b image = renderMapPreview(map, cam, options);
    const cv::Vec3b c = image(kH / 2, kW / 2);
    EXPECT_GT(c[2], 100) << "order " << order;  // red (BGR)
    EXPECT_LT(c[0], 30) << "order " << order;   // no blue
  }
}

TEST(MapPreview, NearRedTriangleHidesFarBlueTriangle) {
  const MapPreviewOptions options = testOptions();
  const PreviewCamera cam = frontCamera(0.0f, 200.0f);
  PlyData map;
  for (float z : {4.0f, 2.0f}) {  // far first
    map.vertices.emplace_back(-z, -z, z);
    map.vertices.emplace_back(z, -z, z);
    map.vertices.emplace_back(0, z, z);
  }
  for (int i = 0; i < 3; ++i) map.colors.push_back({0, 0, 255});
  for (int i = 0; i < 3; ++i) map.colors.push_back({255, 0, 0});
  map.triangles = {{0, 1, 2}, {3, 4, 5}};
  const cv::Mat3b image = renderMapPreview(map, cam, options);
  const cv::Vec3b c = image(kH / 2, kW / 2);
  EXPECT_GT(c[2], 100);
  EXPECT_LT(c[0], 30);
}

/// A 4 x 3 m floor (z = 0) with a 0.5 m box on it; z is up.
std::vector<Eigen::Vector3f> room(std::size_t n, std::mt19937* rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Eigen::Vector3f> points;
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 5 == 0) {
      points.emplace_back(1.0f + 0.5f * u(*rng), 1.0f + 0.5f * u(*rng), 0.5f);
    } else {
      points.emplace_back(4.0f * u(*rng), 3.0f * u(*rng), 0.02f * u(*rng));
    }
  }
  return points;
}

TEST(MapPreview, UpFromCamerasThatYawAndPitch) {
  std::mt19937 rng(7);
  const std::vector<Eigen::Vector3f> points = room(20000, &rng);
  std::vector<TimedPose> trajectory;
  for (int i = 0; i < 40; ++i) {
    // Camera looking horizontally along world x (z_C = x_W, y_C = -z_W), then yawed and pitched.
    Eigen::Matrix3d R0;
    R0.col(0) = -Eigen::Vector3d::UnitY();
    R0.col(1) = -Eigen::Vector3d::UnitZ();
    R0.col(2) = Eigen::Vector3d::UnitX();
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.05 * i, Eigen::Vector3d::UnitZ()) * R0 *
                              Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX());  // pitch
    TimedPose pose{static_cast<double>(i), Eigen::Isometry3d::Identity()};
    pose.T_W_C.linear() = R;
    trajectory.push_back(pose);
  }
  const Eigen::Vector3f up = estimateUp(points, trajectory);
  EXPECT_GT(up.dot(Eigen::Vector3f::UnitZ()), std::cos(2.0 * M_PI / 180.0));
  // Without cameras: the smallest principal axis, which the off-centre box tilts (~3 degrees).
  EXPECT_GT(estimateUp(points, {}).z(), std::cos(5.0 * M_PI / 180.0));
}

TEST(MapPreview, CamerasFrameTheMapAndTopLooksDown) {
  std::mt19937 rng(3);
  const std::vector<Eigen::Vector3f> points = room(20000, &rng);
  const MapPreviewOptions options = testOptions();
  const std::vector<PreviewCamera> cams = choosePreviewCameras(points, {}, options);
  ASSERT_EQ(cams.size(), 3u);
  EXPECT_EQ(cams[0].name, "top");
  EXPECT_TRUE(cams[0].orthographic);
  // Top camera's viewing axis (z_C in world) is along -up.
  const Eigen::Vector3f z_W = cams[0].T_C_W.linear().row(2).transpose();
  EXPECT_GT(std::abs(z_W.z()), std::cos(5.0 * M_PI / 180.0));  // PCA up, see above
  for (const PreviewCamera& cam : cams) {
    int in_image = 0;
    for (const auto& p_W : points) {
      const Eigen::Vector3f p = cam.T_C_W * p_W;
      if (!cam.orthographic) {
        ASSERT_GT(p.z(), 0.0f) << cam.name << ": point behind the camera";
      }
      const float s = cam.orthographic ? 1.0f : 1.0f / p.z();
      const float u = cam.focal_px * p.x() * s + cam.cx, v = cam.focal_px * p.y() * s + cam.cy;
      in_image += u >= 0 && v >= 0 && u < kW && v < kH;
    }
    EXPECT_GT(in_image, 0.97 * points.size()) << cam.name;
  }
}

TEST(MapPreview, WritesThreePngsAndRenders1500kPointsQuickly) {
  std::mt19937 rng(11);
  PlyData map;
  map.vertices = room(1500000, &rng);
  map.colors.assign(map.vertices.size(), {200, 180, 160});
  const auto dir = test::freshTempDir("map_preview");
  const auto start = std::chrono::steady_clock::now();
  const std::vector<std::string> names = writeMapPreviews(map, {}, dir.string());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(names.size(), 3u);
  for (const std::string& name : names) {
    const cv::Mat image = cv::imread((dir / name).string());
    ASSERT_FALSE(image.empty()) << name;
    EXPECT_EQ(image.cols, MapPreviewOptions{}.width);
  }
  // Budget 2 s on a free core; 4 s here because the test machines are shared.
  EXPECT_LT(seconds, 4.0);
  EXPECT_TRUE(writeMapPreviews(PlyData{}, {}, dir.string()).empty());
}

}  // namespace
}  // namespace dynamap
