// shapesense-shape: voxel clouds → shapes, over LCM (see shape_service.h).
#include <CLI/CLI.hpp>
#include <iostream>

#include "libs/core/error.h"
#include "runtime/lcm/service_loop.h"
#include "services/shape/shape_service.h"

int main(int argc, char** argv) {
  CLI::App app{"shapesense-shape: voxel clouds (and their images) → shapes, over LCM"};
  shapesense::ShapeServiceArgs args;
  std::string lcm_url;
  app.add_option("--config", args.config, "service config (config/shape_service.yaml)");
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
        shapesense::RunShapeService(args, shapesense::StopFlagOnSignals(), std::cerr);
    std::cerr << "shapesense-shape: stopped; " << status.received << " voxel clouds, "
              << status.published << " shapes, " << status.dropped << " voxel clouds dropped, "
              << status.rejected << " rejected, " << status.errors << " errors\n";
  } catch (const shapesense::InputError& e) {
    std::cerr << "shapesense-shape: error: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "shapesense-shape: failed: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
