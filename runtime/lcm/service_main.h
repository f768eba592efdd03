#pragma once

// The command line every sensing service shares (config, LCM URL, rig,
// backgrounds, duration), its error handling and its last words.
#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <ostream>
#include <string>

#include "shapesense/service_status_t.hpp"

namespace shapesense {

struct ServiceArgs {
  std::filesystem::path config;        // empty: defaults (then --rig and --backgrounds are needed)
  std::optional<std::string> lcm_url;  // overrides the config's
  std::filesystem::path rig;           // override the config's
  std::filesystem::path backgrounds;
  double duration_s = 0.0;  // 0: until stopped
};

// Loads and checks everything, then runs until `stop` or the duration;
// returns the last status. Throws InputError on bad input.
using RunServiceFunction = std::function<service_status_t(
    const ServiceArgs& args, const std::atomic<bool>& stop, std::ostream& log)>;

// Parses the command line, runs the service until SIGINT/SIGTERM, and
// prints its counters. Exit codes: 0 done, 1 failed, 2 bad input (the
// message names the file and key), as every shapesense program.
int ServiceMain(int argc, char** argv, const std::string& name, const std::string& description,
                const std::string& example_config, const RunServiceFunction& run);

}  // namespace shapesense
