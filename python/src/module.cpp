// The Python module `dynamap`: dynamap::System with numpy in and out. Errors keep the C++
// messages: ConfigError -> dynamap.ConfigError (a ValueError), std::invalid_argument ->
// ValueError, std::logic_error / std::runtime_error -> RuntimeError.
#include <optional>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "dynamap/system.hpp"
#include "dynamap/system/config_schema.hpp"
#include "dynamap/system/map_store.hpp"
#include "numpy_convert.hpp"

namespace py = pybind11;
using dynamap::System;

namespace {

/// What System.track() returns to Python.
struct PyTrackResult {
  double timestamp_s = 0.0;
  py::array_t<double> pose;
  std::string status;
  py::array_t<std::uint8_t> mask;
  bool is_keyframe = false;
};

std::unique_ptr<System> makeSystem(const std::optional<std::string>& config,
                                   const std::optional<py::dict>& overrides,
                                   const std::optional<std::string>& load_map) {
  const std::vector<std::string> sets =
      overrides ? dynamap::python::overrideStrings(*overrides) : std::vector<std::string>{};
  const std::string path = config.value_or("");
  dynamap::SystemOptions options;
  options.load_map_dir = load_map.value_or("");
  py::gil_scoped_release release;  // loads detector weights, plugins and the saved map
  return System::fromConfig(path, sets, std::move(options));
}

PyTrackResult track(System& system, const py::array& bgr, const py::array& depth,
                    double timestamp_s) {
  py::object keep_bgr;
  py::object keep_depth;
  const cv::Mat bgr_view = dynamap::python::colourView(bgr, &keep_bgr);
  const cv::Mat depth_view = dynamap::python::depthView(depth, &keep_depth);
  dynamap::TrackOutput out;
  {
    py::gil_scoped_release release;  // the arrays are kept alive above; System copies them
    out = system.track(bgr_view, depth_view, timestamp_s);
  }
  PyTrackResult result;
  result.timestamp_s = timestamp_s;
  result.pose = dynamap::python::poseArray(out.T_W_C);
  result.status = dynamap::toString(out.status);
  result.mask = dynamap::python::maskArray(out.dynamic_mask);
  result.is_keyframe = out.is_keyframe;
  return result;
}

py::list posesToList(const std::vector<dynamap::TimedPose>& poses) {
  py::list out;
  for (const auto& p : poses) {
    out.append(py::make_tuple(p.timestamp_s, dynamap::python::poseArray(p.T_W_C)));
  }
  return out;
}

void saveTrajectory(const System& system, const std::string& path) {
  dynamap::writeTrajectory(path, system.trajectory());
}

}  // namespace

PYBIND11_MODULE(dynamap, m) {
  m.doc() =
      "dynamap: RGB-D visual SLAM for dynamic scenes (tracking, motion-area removal, dense "
      "mapping).\n\n"
      "    system = dynamap.System('config/default.yaml', {'mapping.backend': 'vdb_tsdf'})\n"
      "    result = system.track(bgr, depth, timestamp_s)  # numpy in, numpy out\n"
      "    system.export_map('out/map')\n";

  py::register_exception<dynamap::ConfigError>(m, "ConfigError", PyExc_ValueError);
  py::register_exception<dynamap::MapFileError>(m, "MapFileError", PyExc_ValueError);

  py::class_<PyTrackResult>(m, "TrackResult", "Outcome of System.track() for one frame.")
      .def_readonly("timestamp_s", &PyTrackResult::timestamp_s, "The frame's timestamp (s).")
      .def_readonly("pose", &PyTrackResult::pose,
                    "4x4 float64 camera-to-world pose T_W_C (the last known one when lost).")
      .def_readonly("status", &PyTrackResult::status,
                    "'tracked', 'depth' (posed by the static depth alone), 'relocalized' or "
                    "'lost'.")
      .def_readonly("mask", &PyTrackResult::mask,
                    "HxW uint8 dynamic mask of the frame, 255 = moving, 0 = static.")
      .def_readonly("is_keyframe", &PyTrackResult::is_keyframe,
                    "True when the frame became a keyframe (handed to the mapping backend).")
      .def("__repr__", [](const PyTrackResult& r) {
        return "TrackResult(timestamp_s=" + std::to_string(r.timestamp_s) + ", status='" +
               r.status + "', is_keyframe=" + (r.is_keyframe ? "True" : "False") + ")";
      });

  py::class_<System>(m, "System",
                     "Tracking + motion-area removal + dense mapping of one RGB-D sequence.\n\n"
                     "Not thread-safe: call its methods from one thread at a time (it runs its "
                     "own bundle-adjustment, detector and mapping threads). track(), finish() "
                     "and export_map() release the GIL.")
      .def(py::init(&makeSystem), py::arg("config") = py::none(), py::arg("overrides") = py::none(),
           py::arg("load_map") = py::none(),
           "System(config=None, overrides=None, load_map=None)\n\n"
           "config: path of a YAML configuration (as `dynamap run --config`); None = the "
           "defaults in code.\noverrides: {'section.key': value} applied after the file, as "
           "`--set section.key=value` (bool, int, float, str or a list of them).\n"
           "load_map: a folder save_map() wrote: start in that map (relocalize in it, poses "
           "in its frame, new keyframes extend it), as `dynamap run --load-map`.\n"
           "Raises ConfigError (a ValueError) for an unknown key or a bad value, MapFileError "
           "(a ValueError) for a missing, corrupt or mismatched saved map (names the file and "
           "field), RuntimeError for an unknown mapping backend or missing detector files.")
      .def("track", &track, py::arg("bgr"), py::arg("depth"), py::arg("timestamp_s"),
           "track(bgr, depth, timestamp_s) -> TrackResult\n\n"
           "bgr: HxWx3 uint8 colour image in BGR order (as cv2.imread gives it).\n"
           "depth: HxW uint16 depth in units of camera.depth_scale per metre (TUM PNG: 5000) or "
           "float32 metres; 0 = no reading.\ntimestamp_s: the frame's time in seconds.\n"
           "Raises ValueError for a wrong dtype or shape, RuntimeError after finish().")
      .def(
          "trajectory", [](const System& s) { return posesToList(s.trajectory()); },
          "trajectory() -> list[(timestamp_s, 4x4 pose)]: every tracked frame, each pose "
          "recomposed with its keyframe's latest optimised pose (final after finish()).")
      .def(
          "keyframes", [](const System& s) { return posesToList(s.keyframes()); },
          "keyframes() -> list[(timestamp_s, 4x4 pose)]: keyframe poses, latest optimised.")
      .def(
          "frame_statuses",
          [](const System& s) {
            std::vector<std::string> out;
            for (const auto status : s.frameStatuses()) out.emplace_back(dynamap::toString(status));
            return out;
          },
          "frame_statuses() -> list[str], parallel to trajectory().")
      .def("save_trajectory", &saveTrajectory, py::arg("path"),
           "save_trajectory(path): the trajectory in TUM format, exactly as `dynamap run` "
           "writes OUT/trajectory.txt.")
      .def("finish", &System::finish, py::call_guard<py::gil_scoped_release>(),
           "finish(): final bundle adjustment, final poses to the mapper, waits for mapping. "
           "Idempotent.")
      .def("export_map", &System::exportMap, py::arg("directory"),
           py::call_guard<py::gil_scoped_release>(),
           "export_map(directory): finish(), then writes the backend's map files there.")
      .def("save_map", &System::saveMap, py::arg("directory"),
           py::call_guard<py::gil_scoped_release>(),
           "save_map(directory): finish(), then writes what a later run needs to start in this "
           "map (map.sqlite: keyframes, landmarks, poses, camera, format version; map/: the "
           "backend's files). Load it with System(..., load_map=directory).")
      .def("export_map_snapshot", &System::exportMapSnapshot, py::arg("directory"),
           py::call_guard<py::gil_scoped_release>(),
           "export_map_snapshot(directory): the map as it is now, during the run, without "
           "finishing (the keyframes of the last mapping.window_after_s are not in it yet); "
           "writes the backend's map files there. After finish(): the final map.")
      .def_property_readonly(
          "counts",
          [](const System& s) {
            const auto c = s.counts();
            py::dict d;
            d["frames"] = c.frames;
            d["tracked"] = c.tracked;
            d["relocalized"] = c.relocalized;
            d["posed_by_depth"] = c.posed_by_depth;
            d["lost"] = c.lost;
            d["keyframes"] = c.keyframes;
            d["culled_keyframes"] = c.culled_keyframes;
            d["mapped_keyframes"] = c.mapped_keyframes;
            d["map_elements"] = c.map_elements;
            d["loaded_keyframes"] = c.loaded_keyframes;
            d["loaded_map_elements"] = c.loaded_map_elements;
            return d;
          },
          "Frame and keyframe counts so far (dict).");
}
