#include <cstdlib>
#include <fstream>

#include <gtest/gtest.h>
#include <unistd.h>
#include <opencv2/imgcodecs.hpp>

#include "dynamap/core/dynamic/dynamic_motion_filter.hpp"
#include "dynamap/core/dynamic/object_detector.hpp"
#include "test_paths.hpp"

namespace dynamap {
namespace {

namespace fs = std::filesystem;

/// Writes tiny ONNX graphs with a known output (Debian's python3-onnx): the image blob is
/// reshaped to the output shape, multiplied by 0 and added to a constant holding known boxes.
/// YOLOv5: input 1x3x85x85 -> 1x255x85; YOLOv8: input 1x3x84x84 -> 1x84x252.
const char* kGenerator = R"PY(
import sys, numpy as np, onnx
from onnx import helper, TensorProto, numpy_helper
def make(path, const, size):
    X = helper.make_tensor_value_info('images', TensorProto.FLOAT, [1, 3, size, size])
    Y = helper.make_tensor_value_info('output', TensorProto.FLOAT, list(const.shape))
    inits = [numpy_helper.from_array(const.astype(np.float32), 'C'),
             numpy_helper.from_array(np.zeros(const.shape, np.float32), 'Z'),
             numpy_helper.from_array(np.array(const.shape, np.int64), 'S')]
    nodes = [helper.make_node('Reshape', ['images', 'S'], ['r']),
             helper.make_node('Mul', ['r', 'Z'], ['rz']),
             helper.make_node('Add', ['rz', 'C'], ['output'])]
    g = helper.make_graph(nodes, 'g', [X], [Y], initializer=inits)
    m = helper.make_model(g, opset_imports=[helper.make_opsetid('', 11)])
    m.ir_version = 6
    onnx.checker.check_model(m)
    onnx.save(m, path)
out = sys.argv[1]
v5 = np.zeros((1, 255, 85))
v5[0, 3, :6] = [40, 40, 20, 30, 0.9, 0.8]                 # person, score 0.72
v5[0, 4, :6] = [41, 40, 20, 30, 0.9, 0.5]                 # duplicate, score 0.45
v5[0, 7, :5] = [60, 50, 10, 10, 0.8]; v5[0, 7, 5 + 16] = 0.9  # dog, score 0.72
v5[0, 9, :6] = [20, 20, 10, 10, 0.05, 0.9]                # below threshold
make(out + '/v5.onnx', v5, 85)
v8 = np.zeros((1, 84, 252))
v8[0, :5, 3] = [40, 40, 20, 30, 0.7]                      # person 0.7
v8[0, :4, 8] = [60, 50, 10, 10]; v8[0, 4 + 16, 8] = 0.6  # dog 0.6
v8[0, :5, 11] = [20, 20, 10, 10, 0.1]                     # below threshold
make(out + '/v8.onnx', v8, 84)
)PY";

class GeneratedOnnx : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: ctest runs each test in its own process, in parallel.
    dir_ = test::freshTempDir("dyn_onnx_" + std::to_string(::getpid()));
    if (!fs::exists("/usr/bin/python3")) return;
    std::ofstream(dir_ / "gen.py") << kGenerator;
    const std::string cmd = "/usr/bin/python3 " + (dir_ / "gen.py").string() + " " + dir_.string();
    ok_ = std::system(cmd.c_str()) == 0;
  }
  void SetUp() override {
    if (!fs::exists("/usr/bin/python3")) GTEST_SKIP() << "/usr/bin/python3 not installed";
    ASSERT_TRUE(ok_) << "python3-onnx failed to generate the test graphs";
  }
  static DetectorOptions options(const std::string& kind, const std::string& file, int size) {
    DetectorOptions o;
    o.kind = kind;
    o.model_weights = (dir_ / file).string();
    o.input_width = o.input_height = size;
    o.nms.kind = NmsKind::kPlain;
    return o;
  }
  static fs::path dir_;
  static bool ok_;
};
fs::path GeneratedOnnx::dir_;
bool GeneratedOnnx::ok_ = false;

// A 170x85 image letterboxed into 85x85: scale 0.5, resized to 85x43, padded 21 rows on top.
// Input box (cx 40, cy 40, w 20, h 30) -> image x0 = (40-10)/0.5 = 60, y0 = (40-15-21)/0.5 = 8.
const cv::Rect2f kPersonV5(60, 8, 40, 60);

TEST_F(GeneratedOnnx, YoloV5DecodingUndoesTheLetterbox) {
  auto det = makeObjectDetector(options("yolov5_onnx", "v5.onnx", 85), ClassTable(DynamicConfig{}));
  const auto dets = det->detect(cv::Mat(85, 170, CV_8UC3, cv::Scalar::all(50)));
  ASSERT_EQ(dets.size(), 2u);  // duplicate suppressed, faint box dropped
  EXPECT_EQ(dets[0].class_id, 0);
  EXPECT_NEAR(dets[0].score, 0.72f, 1e-4);
  EXPECT_NEAR(dets[0].box.x, kPersonV5.x, 0.01);
  EXPECT_NEAR(dets[0].box.y, kPersonV5.y, 0.01);
  EXPECT_NEAR(dets[0].box.width, kPersonV5.width, 0.01);
  EXPECT_NEAR(dets[0].box.height, kPersonV5.height, 0.01);
  EXPECT_EQ(dets[1].class_id, 16);
  EXPECT_NEAR(dets[1].box.x, (60 - 5) / 0.5, 0.01);
  EXPECT_NEAR(dets[1].box.y, (50 - 5 - 21) / 0.5, 0.01);
}

TEST_F(GeneratedOnnx, YoloV8DecodingReadsTheTransposedLayout) {
  // 84x84 input, square 84x84 image: no letterbox.
  auto det = makeObjectDetector(options("yolov8_onnx", "v8.onnx", 84), ClassTable(DynamicConfig{}));
  const auto dets = det->detect(cv::Mat(84, 84, CV_8UC3, cv::Scalar::all(50)));
  ASSERT_EQ(dets.size(), 2u);
  EXPECT_EQ(dets[0].class_id, 0);
  EXPECT_NEAR(dets[0].score, 0.7f, 1e-4);
  EXPECT_NEAR(iou(dets[0].box, cv::Rect2f(30, 25, 20, 30)), 1.f, 1e-4);
  EXPECT_EQ(dets[1].class_id, 16);
  EXPECT_NEAR(iou(dets[1].box, cv::Rect2f(55, 45, 10, 10)), 1.f, 1e-4);
}

TEST_F(GeneratedOnnx, WrongLayoutIsAnErrorNamingTheFile) {
  // The YOLOv8 graph handed over as YOLOv5 (and vice versa) is refused at construction.
  for (const auto& [kind, file, size] :
       {std::tuple{"yolov5_onnx", "v8.onnx", 84}, {"yolov8_onnx", "v5.onnx", 85}}) {
    try {
      makeObjectDetector(options(kind, file, size), ClassTable(DynamicConfig{}));
      FAIL() << kind << " accepted " << file;
    } catch (const DetectorError& e) {
      EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
    }
  }
}

TEST(DetectorDecode, DarknetRowsAreNormalisedCentreBoxes) {
  cv::Mat rows = cv::Mat::zeros(2, 85, CV_32F);
  float* r = rows.ptr<float>(0);
  r[0] = 0.5f, r[1] = 0.5f, r[2] = 0.25f, r[3] = 0.5f, r[4] = 0.9f, r[5] = 0.8f;
  rows.at<float>(1, 4) = 0.1f;
  const auto d = decodeDarknet(rows, cv::Size(640, 480), 0.25f);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_NEAR(iou(d[0].box, cv::Rect2f(240, 120, 160, 240)), 1.f, 1e-5);
}

DynamicConfig darknetConfig() {
  DynamicConfig c;
  c.model_cfg = (test::sharedModels() / "yolo-fastest/yolo-fastest-1.1-xl.cfg").string();
  c.model_weights = (test::sharedModels() / "yolo-fastest/yolo-fastest-1.1-xl.weights").string();
  return c;
}

TEST(Darknet, YoloFastestFindsThePeopleInBusJpg) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const DynamicConfig c = darknetConfig();
  auto det = makeObjectDetector(detectorOptions(c), ClassTable(c));
  const cv::Mat bus = cv::imread((test::sharedData() / "photos/bus.jpg").string());
  ASSERT_FALSE(bus.empty());
  // Hand-labelled boxes (tests/dynamic/data/person_boxes.csv).
  const std::vector<cv::Rect2f> people{
      {50, 398, 197, 505}, {224, 406, 121, 454}, {668, 395, 142, 485}, {0, 550, 77, 322}};
  int found = 0;
  const auto dets = det->detect(bus);
  for (const auto& p : people) {
    found += std::any_of(dets.begin(), dets.end(), [&](const Detection& d) {
      return d.class_id == 0 && iou(d.box, p) >= 0.5f;
    });
  }
  EXPECT_GE(found, 3);
}

std::string constructionError(const DynamicConfig& c) {
  try {
    makeMotionFilter(c, PinholeCamera{}, nullptr);
  } catch (const DetectorError& e) {
    return e.what();
  }
  return "";
}

TEST(Darknet, MissingOrWrongModelIsAnErrorNamingTheFile) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  DynamicConfig c = darknetConfig();
  c.model_weights = "/nonexistent/yolo.weights";
  EXPECT_NE(constructionError(c).find("/nonexistent/yolo.weights"), std::string::npos);

  const fs::path dir = test::freshTempDir("dyn_bad_model");
  std::ofstream(dir / "junk.cfg") << "this is not a darknet cfg\n";
  c = darknetConfig();
  c.model_cfg = (dir / "junk.cfg").string();
  EXPECT_NE(constructionError(c).find("junk.cfg"), std::string::npos);

  std::ofstream(dir / "junk.onnx") << "not a protobuf";
  c.detector = "yolov5_onnx";
  c.model_weights = (dir / "junk.onnx").string();
  EXPECT_NE(constructionError(c).find("junk.onnx"), std::string::npos);

  // A real network with another layout (NanoDet) handed over as YOLOv5.
  c.model_weights = (test::sharedModels() / "nanodet/nanodet.onnx").string();
  c.input_width = c.input_height = 320;
  EXPECT_NE(constructionError(c).find("nanodet.onnx"), std::string::npos);
}

// OpenCV's Darknet reader accepts a short .weights file; the detector must not.
TEST(Darknet, TruncatedWeightsAreAnErrorNamingTheFile) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const DynamicConfig good = darknetConfig();
  const auto full = fs::file_size(good.model_weights);
  std::vector<char> bytes(full);
  std::ifstream(good.model_weights, std::ios::binary)
      .read(bytes.data(), static_cast<std::streamsize>(full));
  const fs::path dir = test::freshTempDir("dyn_trunc_weights");
  // Cut in the middle, and by a single float at the end.
  for (const std::size_t keep : {full / 2, full - 4}) {
    const fs::path path = dir / ("cut" + std::to_string(keep) + ".weights");
    std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(keep));
    DynamicConfig c = good;
    c.model_weights = path.string();
    const std::string error = constructionError(c);
    EXPECT_NE(error.find(path.string()), std::string::npos) << error;
    EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  }
  EXPECT_EQ(constructionError(good), "");
}

TEST(NanoDet, FindsThePersonInPersonJpg) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  DynamicConfig c;
  c.detector = "nanodet_onnx";
  c.model_weights = (test::sharedModels() / "nanodet/nanodet.onnx").string();
  auto det = makeObjectDetector(detectorOptions(c), ClassTable(c));
  const cv::Mat img = cv::imread((test::sharedData() / "photos/person.jpg").string());
  const auto dets = det->detect(img);
  EXPECT_TRUE(std::any_of(dets.begin(), dets.end(), [](const Detection& d) {
    return d.class_id == 0 && iou(d.box, cv::Rect2f(190, 98, 85, 277)) >= 0.5f;
  }));
}

}  // namespace
}  // namespace dynamap
