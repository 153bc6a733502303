#include "numpy_convert.hpp"

#include <stdexcept>

namespace py = pybind11;

namespace dynamap::python {
namespace {

std::string shapeText(const py::array& a) {
  std::string text = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) {
    text += (i > 0 ? ", " : "") + std::to_string(a.shape(i));
  }
  return text + (a.ndim() == 1 ? ",)" : ")");
}

std::string dtypeText(const py::array& a) { return py::str(a.dtype()).cast<std::string>(); }

cv::Mat view(const py::array& array, int type, py::object* keep) {
  const auto contiguous = py::array::ensure(array, py::array::c_style);
  *keep = contiguous;
  const int rows = static_cast<int>(contiguous.shape(0));
  const int cols = static_cast<int>(contiguous.shape(1));
  return cv::Mat(rows, cols, type, const_cast<void*>(contiguous.data()));
}

std::string scalarText(const py::handle& value) {
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (py::isinstance<py::int_>(value) || py::isinstance<py::float_>(value)) {
    return py::repr(value).cast<std::string>();
  }
  throw std::invalid_argument(
      "override values must be str, int, float, bool or a list of "
      "them, got " +
      py::str(value.get_type()).cast<std::string>());
}

}  // namespace

cv::Mat colourView(const py::array& array, py::object* keep) {
  if (array.ndim() != 3 || array.shape(2) != 3) {
    throw std::invalid_argument("colour image must have shape (H, W, 3) (BGR), got " +
                                shapeText(array));
  }
  if (!py::isinstance<py::array_t<std::uint8_t>>(array)) {
    throw std::invalid_argument("colour image must have dtype uint8, got " + dtypeText(array));
  }
  return view(array, CV_8UC3, keep);
}

cv::Mat depthView(const py::array& array, py::object* keep) {
  if (array.ndim() != 2) {
    throw std::invalid_argument("depth image must have shape (H, W), got " + shapeText(array));
  }
  if (py::isinstance<py::array_t<std::uint16_t>>(array)) return view(array, CV_16UC1, keep);
  if (py::isinstance<py::array_t<float>>(array)) return view(array, CV_32FC1, keep);
  throw std::invalid_argument(
      "depth image must have dtype uint16 (units of camera.depth_scale per metre) or float32 "
      "(metres), got " +
      dtypeText(array));
}

py::array_t<double> poseArray(const Eigen::Isometry3d& T) {
  py::array_t<double> out({4, 4});
  auto m = out.mutable_unchecked<2>();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = T.matrix()(r, c);
  }
  return out;
}

Eigen::Isometry3d poseFromArray(const py::array& array) {
  if (array.ndim() != 2 || array.shape(0) != 4 || array.shape(1) != 4) {
    throw std::invalid_argument("pose must have shape (4, 4), got " + shapeText(array));
  }
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
  const auto m = a.unchecked<2>();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) T.matrix()(r, c) = m(r, c);
  }
  return T;
}

py::array_t<std::uint8_t> maskArray(const cv::Mat& mask) {
  py::array_t<std::uint8_t> out({mask.rows, mask.cols});
  auto m = out.mutable_unchecked<2>();
  for (int r = 0; r < mask.rows; ++r) {
    const auto* row = mask.ptr<std::uint8_t>(r);
    for (int c = 0; c < mask.cols; ++c) m(r, c) = row[c];
  }
  return out;
}

std::vector<std::string> overrideStrings(const py::dict& overrides) {
  std::vector<std::string> out;
  for (const auto& [key, value] : overrides) {
    std::string text;
    if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
      for (const auto& item : value) text += (text.empty() ? "" : ",") + scalarText(item);
    } else {
      text = scalarText(value);
    }
    out.push_back(py::str(key).cast<std::string>() + "=" + text);
  }
  return out;
}

}  // namespace dynamap::python
