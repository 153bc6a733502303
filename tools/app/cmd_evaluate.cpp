#include <iostream>

#include "commands.hpp"

namespace dynamap {

// Placeholder until the evaluation module lands (issue 2).
void addEvaluateCommand(CLI::App& app, int* exit_code) {
  auto* cmd = app.add_subcommand("evaluate", "ATE/RPE of an estimated trajectory vs ground truth");
  cmd->callback([exit_code] {
    std::cerr << "dynamap evaluate: not implemented yet\n";
    *exit_code = 2;
  });
}

}  // namespace dynamap
