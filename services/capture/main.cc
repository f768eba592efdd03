// shapesense-capture: serves cameras on LCM (see capture_service.h), or with
// `background` stores each camera's background image. Exit codes as every
// shapesense program: 0 done, 1 failed, 2 bad input.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "libs/core/error.h"
#include "runtime/command_line.h"
#include "runtime/lcm/service_loop.h"
#include "runtime/process/signal_thread.h"
#include "services/capture/background_capture.h"
#include "services/capture/capture_service.h"

namespace shapesense {
namespace {

int Run(int argc, char** argv) {
  KeepFreedMemoryForReuse();
  CLI::App app("shapesense-capture: camera images on LCM (Aravis, V4L2, replay, simulated)");
  std::string config;
  std::vector<std::string> cameras;
  std::optional<double> rate;
  CaptureServiceArgs args;
  app.add_option("--config", config, "service config YAML (config/capture.yaml)");
  app.add_option("--camera", cameras,
                 "NAME=BACKEND:DEVICE, repeatable (cam0=aravis:127.0.0.1, "
                 "cam1=v4l2:/dev/video0, cam2=replay:DIR, cam3=simulated:)");
  app.add_option("--rate", rate, "software trigger rate, Hz (overrides trigger_rate_hz)");
  app.add_option("--lcm-url", args.lcm_url, "LCM URL (default: LCM_DEFAULT_URL or LCM's default)");
  app.add_option("--duration", args.duration_s,
                 "stop after this many seconds (default: run until stopped)");
  CLI::App* background = app.add_subcommand(
      "background", "store the median of N frames per camera as OUT/<camera>.png");
  std::optional<int> frames;
  std::optional<std::string> out;
  background->add_option("--frames", frames, "frames per camera (default background.frames)");
  background->add_option("--out", out, "output folder (default background.out)");
  if (const std::optional<int> exit_code = ParseCommandLine(app, argc, argv)) return *exit_code;
  const std::atomic<bool>& stop = StopFlagOnSignals();
  try {
    args.options = LoadCaptureOptions(config, cameras, rate);
    if (background->parsed()) {
      if (frames) args.options.background.frames = *frames;
      if (out) args.options.background.out = *out;
      RunBackgroundCapture({args.options, {}, {}}, stop);
      return 0;
    }
    const CaptureSummary summary = RunCaptureService(args, stop);
    for (const auto& [name, camera] : summary.cameras) {
      std::printf("%s: %lld images published, %lld outages\n", name.c_str(),
                  static_cast<long long>(camera.published), static_cast<long long>(camera.outages));
    }
    return 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "shapesense-capture: error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "shapesense-capture: failed: %s\n", e.what());
    return kExitFailed;
  }
}

}  // namespace
}  // namespace shapesense

int main(int argc, char** argv) { return shapesense::Run(argc, argv); }
