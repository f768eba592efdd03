// shapesense: the command-line tools. Each subcommand lives in its own file
// as AddXCommand(app) over a testable RunX(...).
#include <CLI/CLI.hpp>
#include <iostream>

#include "clients/tools/attack/attack_command.h"
#include "clients/tools/calibrate/calibrate_command.h"
#include "clients/tools/config_command.h"
#include "clients/tools/demo_command.h"
#include "clients/tools/estimate/estimate_command.h"
#include "clients/tools/keygen_command.h"
#include "clients/tools/monitor/monitor_command.h"
#include "clients/tools/offline_command.h"
#include "clients/tools/replay/replay_command.h"
#include "clients/tools/rig/rig_command.h"
#include "clients/tools/tape_colour/tape_colour_command.h"
#include "libs/core/error.h"
#include "runtime/command_line.h"

int main(int argc, char** argv) {
  CLI::App app{"shapesense: 3-D shape sensing of continuum manipulators"};
  app.require_subcommand(1);
  shapesense::AddOfflineCommand(app);
  shapesense::AddDemoCommand(app);
  shapesense::AddConfigCommand(app);
  shapesense::AddCalibrateCommand(app);
  shapesense::AddTapeColourCommand(app);
  shapesense::AddEstimateCommand(app);
  shapesense::AddMonitorCommand(app);
  shapesense::AddReplayCommand(app);
  shapesense::AddRigCommand(app);
  shapesense::AddKeygenCommand(app);
  shapesense::AddAttackCommand(app);
  // The subcommands run inside the parse (their callbacks), so their errors
  // come out of it too.
  try {
    if (const std::optional<int> code = shapesense::ParseCommandLine(app, argc, argv)) return *code;
  } catch (const shapesense::InputError& e) {
    std::cerr << "shapesense: error: " << e.what() << '\n';
    return shapesense::kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "shapesense: failed: " << e.what() << '\n';
    return shapesense::kExitFailed;
  }
  return 0;
}
