#include <algorithm>

#include <opencv2/imgproc.hpp>

#include "dynamap/core/dynamic/object_detector.hpp"

namespace dynamap {

namespace {

/// Views a 3-D 1 x A x B blob (or a 2-D A x B matrix) as an A x B matrix (no copy).
cv::Mat asMatrix(const cv::Mat& blob) {
  if (blob.dims == 2) return blob;
  CV_Assert(blob.dims == 3 && blob.size[0] == 1 && blob.type() == CV_32F);
  return cv::Mat(blob.size[1], blob.size[2], CV_32F, const_cast<uchar*>(blob.ptr()));
}

Detection fromCentre(float cx, float cy, float w, float h, const Letterbox& g, int cls,
                     float score) {
  const float s = static_cast<float>(g.scale);
  const float x0 = (cx - 0.5f * w - static_cast<float>(g.pad_x)) / s;
  const float y0 = (cy - 0.5f * h - static_cast<float>(g.pad_y)) / s;
  return Detection{cv::Rect2f(x0, y0, w / s, h / s), cls, score};
}

}  // namespace

cv::Mat letterboxImage(const cv::Mat& bgr, int width, int height, Letterbox* geometry) {
  const double scale =
      std::min(static_cast<double>(width) / bgr.cols, static_cast<double>(height) / bgr.rows);
  const int w = static_cast<int>(std::round(bgr.cols * scale));
  const int h = static_cast<int>(std::round(bgr.rows * scale));
  const int pad_x = (width - w) / 2;
  const int pad_y = (height - h) / 2;
  cv::Mat canvas(height, width, CV_8UC3, cv::Scalar(114, 114, 114));
  cv::Mat resized;
  cv::resize(bgr, resized, cv::Size(w, h), 0, 0, cv::INTER_LINEAR);
  resized.copyTo(canvas(cv::Rect(pad_x, pad_y, w, h)));
  if (geometry != nullptr) *geometry = Letterbox{scale, double(pad_x), double(pad_y)};
  return canvas;
}

std::vector<Detection> decodeYoloV5(const cv::Mat& output, const Letterbox& geometry,
                                    float min_score) {
  const cv::Mat m = asMatrix(output);
  std::vector<Detection> out;
  for (int i = 0; i < m.rows; ++i) {
    const float* r = m.ptr<float>(i);
    const float obj = r[4];
    if (obj < min_score) continue;
    for (int c = 5; c < m.cols; ++c) {
      const float score = obj * r[c];
      if (score >= min_score)
        out.push_back(fromCentre(r[0], r[1], r[2], r[3], geometry, c - 5, score));
    }
  }
  return out;
}

std::vector<Detection> decodeYoloV8(const cv::Mat& output, const Letterbox& geometry,
                                    float min_score) {
  const cv::Mat m = asMatrix(output);  // (4 + C) x N
  std::vector<Detection> out;
  for (int i = 0; i < m.cols; ++i) {
    for (int c = 4; c < m.rows; ++c) {
      const float score = m.at<float>(c, i);
      if (score < min_score) continue;
      out.push_back(fromCentre(m.at<float>(0, i), m.at<float>(1, i), m.at<float>(2, i),
                               m.at<float>(3, i), geometry, c - 4, score));
    }
  }
  return out;
}

std::vector<Detection> decodeDarknet(const cv::Mat& output, const cv::Size& image_size,
                                     float min_score) {
  const cv::Mat m = asMatrix(output);
  const Letterbox unit{1.0, 0.0, 0.0};
  std::vector<Detection> out;
  for (int i = 0; i < m.rows; ++i) {
    const float* r = m.ptr<float>(i);
    if (r[4] < min_score) continue;  // class scores <= objectness
    for (int c = 5; c < m.cols; ++c) {
      if (r[c] < min_score) continue;
      out.push_back(fromCentre(r[0] * image_size.width, r[1] * image_size.height,
                               r[2] * image_size.width, r[3] * image_size.height, unit, c - 5,
                               r[c]));
    }
  }
  return out;
}

}  // namespace dynamap
