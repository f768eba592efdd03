// shapesense-replay-dev: `shapesense replay` on its own, for development
// until the lead wires AddReplayCommand into `shapesense`.
#include <CLI/CLI.hpp>
#include <iostream>

#include "clients/tools/replay/replay_command.h"
#include "libs/core/error.h"

int main(int argc, char** argv) {
  CLI::App app{"shapesense-replay-dev: the replay command alone"};
  app.require_subcommand(1);
  shapesense::AddReplayCommand(app);
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
