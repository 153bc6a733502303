// dynamap export: converts a saved map (cloud.ply / mesh.ply) to PLY, PCD, XYZ or OBJ.
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "map_export.hpp"

namespace dynamap {
namespace {

struct ExportArgs {
  std::string map;
  std::string to;
};

int runExport(const ExportArgs& args) {
  const MapExportResult result = exportMap(args.map, args.to);
  std::cout << "exported " << result.points << " points";
  if (result.triangles > 0) std::cout << " and " << result.triangles << " triangles";
  std::cout << " from " << result.source << " to " << args.to << "\n";
  if (result.dropped_faces) {
    std::cout << "note: " << args.to << " keeps the mesh vertices only (no faces)\n";
  }
  return 0;
}

}  // namespace

void addExportCommand(CLI::App& app, int* exit_code) {
  auto* cmd = app.add_subcommand(
      "export", "Convert a saved map (OUT/map or a .ply file) to .ply, .pcd, .xyz or .obj");
  auto args = std::make_shared<ExportArgs>();
  cmd->add_option("--map", args->map,
                  "map folder of a run (holding cloud.ply or mesh.ply) or a .ply file")
      ->required();
  cmd->add_option("--to", args->to, "output file; its extension picks the format")->required();
  cmd->callback([args, exit_code] { *exit_code = runExport(*args); });
}

}  // namespace dynamap
