#pragma once

#include <CLI/CLI.hpp>

namespace shapesense {

// Registers `shapesense demo`: the live pipeline on the virtual rig as
// separate programs (clients/tools/demo/live_demo.h); with --offline, the
// chain in one process with overlay pictures (clients/tools/demo/offline_demo.h).
void AddDemoCommand(CLI::App& app);

}  // namespace shapesense
