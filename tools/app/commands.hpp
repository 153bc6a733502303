#pragma once

#include <CLI/CLI.hpp>

namespace dynamap {

/// Each subcommand adds itself to the app and sets its own callback. The callback stores the
/// process exit code in `*exit_code`. Explicit registry: main.cpp calls each of these.
void addRunCommand(CLI::App& app, int* exit_code);
void addEvaluateCommand(CLI::App& app, int* exit_code);
void addExportCommand(CLI::App& app, int* exit_code);

}  // namespace dynamap
