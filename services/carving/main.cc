// shapesense-carving: camera images → voxel clouds, over LCM (see carving_service.h).
#include <CLI/CLI.hpp>
#include <iostream>

#include "libs/core/error.h"
#include "runtime/lcm/service_loop.h"
#include "services/carving/carving_service.h"

int main(int argc, char** argv) {
  CLI::App app{"shapesense-carving: frame-sets of camera images → voxel clouds, over LCM"};
  shapesense::CarvingServiceArgs args;
  std::string lcm_url;
  app.add_option("--config", args.config, "service config (config/carving_service.yaml)");
  CLI::Option* url =
      app.add_option("--lcm-url", lcm_url, "LCM provider URL (overrides the config)");
  app.add_option("--rig", args.rig, "rig file (overrides the config)");
  app.add_option("--backgrounds", args.backgrounds,
                 "folder of <camera>.png (overrides the config)");
  app.add_option("--duration", args.duration_s,
                 "stop after this many seconds (default: run until stopped)");
  CLI11_PARSE(app, argc, argv);
  if (url->count() > 0) args.lcm_url = lcm_url;
  try {
    const auto status =
        shapesense::RunCarvingService(args, shapesense::StopFlagOnSignals(), std::cerr);
    std::cerr << "shapesense-carving: stopped; " << status.received << " images, "
              << status.published << " voxel clouds, " << status.dropped << " frame-sets dropped, "
              << status.rejected << " rejected, " << status.errors << " errors\n";
  } catch (const shapesense::InputError& e) {
    std::cerr << "shapesense-carving: error: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "shapesense-carving: failed: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
