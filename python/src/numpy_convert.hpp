#pragma once

#include <map>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace dynamap::python {

/// HxWx3 uint8 (BGR) -> CV_8UC3 header over the array's memory (made C-contiguous first; the
/// array is kept alive in `keep`). Throws std::invalid_argument (ValueError) naming the problem.
cv::Mat colourView(const pybind11::array& array, pybind11::object* keep);
/// HxW uint16 (units of camera.depth_scale per metre) or float32 (metres) -> CV_16UC1 / CV_32FC1
/// header, same rules.
cv::Mat depthView(const pybind11::array& array, pybind11::object* keep);

/// 4x4 float64 array of a pose (a copy).
pybind11::array_t<double> poseArray(const Eigen::Isometry3d& T);
/// 4x4 float-convertible array -> pose; throws std::invalid_argument for another shape.
Eigen::Isometry3d poseFromArray(const pybind11::array& array);
/// HxW uint8 array (a copy) of a CV_8UC1 image.
pybind11::array_t<std::uint8_t> maskArray(const cv::Mat& mask);

/// {"tracking.lk_levels": 4, "dynamic.mode": "off", "x.list": ["a", "b"]} -> "key=value"
/// strings as `dynamap run --set` takes them (bools as true/false, lists comma-separated).
std::vector<std::string> overrideStrings(const pybind11::dict& overrides);

}  // namespace dynamap::python
