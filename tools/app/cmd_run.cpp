#include <iostream>

#include "commands.hpp"

namespace dynamap {

// Placeholder until the pipeline (tools/app/pending/) can be built.
void addRunCommand(CLI::App& app, int* exit_code) {
  auto* cmd = app.add_subcommand("run", "Run SLAM + mapping on a TUM RGB-D sequence");
  cmd->callback([exit_code] {
    std::cerr << "dynamap run: not implemented yet\n";
    *exit_code = 2;
  });
}

}  // namespace dynamap
