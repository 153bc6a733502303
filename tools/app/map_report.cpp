#include "map_report.hpp"

#include <filesystem>
#include <stdexcept>

#include "json_io.hpp"
#include "map_metrics.hpp"

namespace dynamap {
namespace fs = std::filesystem;

std::string mapMetricsJson(const std::string& sequence_dir, const std::string& map_dir,
                           const Alignment& alignment) {
  if (!fs::exists(fs::path(sequence_dir) / "reference_static.ply")) return "";
  fs::path map_file = fs::path(map_dir) / "cloud.ply";
  if (!fs::exists(map_file)) map_file = fs::path(map_dir) / "mesh.ply";
  if (!fs::exists(map_file)) throw std::runtime_error(map_dir + ": no cloud.ply or mesh.ply");

  const ReferenceClouds refs = loadReferenceClouds(sequence_dir);
  Eigen::Isometry3d T_ref_map = Eigen::Isometry3d::Identity();
  T_ref_map.linear() = alignment.scale * alignment.R;  // scale is 1 for a rigid alignment
  T_ref_map.translation() = alignment.t;
  const MapMetrics m = computeMapMetrics(readPlyVertices(map_file.string()), refs, T_ref_map);
  Json json = {{"file", map_file.filename().string()},
               {"map_points_1cm", m.map_points},
               {"accuracy_mean_m", m.accuracy_mean_m},
               {"precision", m.precision},
               {"completeness", m.completeness},
               {"fscore", m.fscore},
               {"ghost_ratio", m.ghost_ratio},
               {"ghost_fragments", m.ghost_fragments},
               {"ghost_fragment_points", m.ghost_fragment_points}};
  if (!refs.settled_points.empty()) {
    json["path_ghost_ratio"] = m.path_ghost_ratio;
    json["settled_completeness"] = m.settled_completeness;
  }
  return dumpJson(json);
}

}  // namespace dynamap
