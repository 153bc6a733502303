#include <exception>
#include <iostream>

#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"dynamap: RGB-D SLAM for dynamic scenes with dense-mapping backends"};
  app.require_subcommand(1);
  int exit_code = 0;
  dynamap::addRunCommand(app, &exit_code);
  dynamap::addEvaluateCommand(app, &exit_code);
  dynamap::addExportCommand(app, &exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "dynamap: error: " << e.what() << "\n";
    return 1;
  }
  return exit_code;
}
