#pragma once

// shapesense-controller (docs/controller.md):
//
//   shapesense-controller --config config/controller_client.yaml
//       [--targets FILE|stream] [--lcm-url URL] [--log-csv PATH] [--log-lcm PATH] [--duration S]
//
// Loads and checks everything, opens the logs, the bus and the actuator
// driver, and runs the control loop until SIGINT / SIGTERM (or the duration).
// Exit codes, as every shapesense program: 0 a clean stop, 1 failed (the
// actuators' link or a fault, LCM), 2 bad input (the message names the file
// and key).

#include <atomic>
#include <ostream>

#include "services/controller/controller_config.h"

namespace shapesense {

// Runs a loaded setup until `stop`; progress and the summary go to `out`.
// Returns the exit code (0, or 1 when the actuators failed). Throws
// InputError when a log cannot be opened, std::runtime_error when LCM
// cannot start.
int RunController(const ControllerSetup& setup, const std::atomic<bool>& stop, std::ostream& out);

int ControllerMain(int argc, char** argv);

}  // namespace shapesense
