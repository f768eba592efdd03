// shapesense-calibrate-dev: `calibrate` alone, for testing it end to end
// before it is linked into `shapesense` (clients/tools/main.cc).
#include <CLI/CLI.hpp>
#include <iostream>

#include "clients/tools/calibrate/calibrate_command.h"
#include "libs/core/error.h"

int main(int argc, char** argv) {
  CLI::App app{"shapesense (calibrate only, development build)"};
  app.require_subcommand(1);
  shapesense::AddCalibrateCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const shapesense::InputError& e) {
    std::cerr << "shapesense: error: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "shapesense: failed: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
