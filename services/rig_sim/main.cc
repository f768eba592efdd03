// shapesense-rig-sim: the virtual rig as real GigE Vision cameras (see rig_sim.h).
#include <malloc.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <opencv2/core/utility.hpp>

#include "libs/core/error.h"
#include "runtime/command_line.h"
#include "runtime/process/signal_thread.h"
#include "services/rig_sim/rig_sim.h"

namespace {

// The cameras' images are rendered several times a second on threads of
// their own: keep the render buffers (megabytes each) in the heap rather
// than mapping and faulting them in anew every image, and let OpenCV work in
// the calling thread rather than oversubscribe the cores with its own pool.
// Together about a sixth less CPU at 30 Hz (the page faults were most of its
// system time).
void TuneForRendering() {
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
  cv::setNumThreads(0);
}

}  // namespace

int main(int argc, char** argv) {
  shapesense::RigSimArgs args;
  CLI::App app{"shapesense-rig-sim: a simulated manipulator served as GigE Vision cameras"};
  app.add_option("--rig", args.rig_path, "rig YAML (default: a synthetic 3-camera rig)");
  app.add_option("--seed", args.seed, "synthetic rig and pixel noise seed");
  app.add_option("--trajectory", args.trajectory_path, "trajectory YAML (config/rig_sim.yaml)");
  app.add_option("--plant", args.plant_path,
                 "plant mode: the controller drives the manipulator (config/rig_plant.yaml)");
  app.add_option("--ips", args.ips, "one address per camera (default 127.0.0.1,127.0.0.2,...)")
      ->delimiter(',');
  app.add_option("--packet-loss", args.packet_loss, "fraction of stream packets dropped (0-1)");
  app.add_option("--lcm-url", args.lcm_url, "LCM provider URL (default: LCM's default)");
  app.add_option("--duration", args.duration_s, "seconds to run (default: until stopped)");
  app.add_option("--answer-delay-ms", args.faults.answer_delay_max_ms,
                 "fault: each image sent up to this long after its exposure (misses triggers)");
  app.add_option("--miss-ratio", args.faults.miss_ratio,
                 "fault: fraction of triggers missed (0-1)");
  app.add_option("--repeat-ratio", args.faults.repeat_ratio,
                 "fault: fraction of triggers answered with the previous image again (0-1)");
  app.add_option("--outage", args.outages, "CAMERA:START_S:DURATION_S, a camera off the network");
  app.add_option("--fault-camera", args.fault_camera, "camera SIGUSR1 stops, SIGUSR2 restarts");
  app.add_flag("--backdrop-only", args.backdrop_only, "no manipulator, no truth (backgrounds)");
  app.add_option("--write-rig", args.write_rig_path, "write the rig in use to this YAML file");
  if (const std::optional<int> exit_code = shapesense::ParseCommandLine(app, argc, argv))
    return *exit_code;
  TuneForRendering();
  std::atomic<bool> stop{false};
  shapesense::RigSimControl control;
  // SIGUSR1 and SIGUSR2 stop and restart the fault camera; the others stop.
  const shapesense::SignalThread signals({SIGINT, SIGTERM, SIGUSR1, SIGUSR2}, [&](int signal) {
    if (signal == SIGUSR1) {
      control.stop_fault_camera = true;
    } else if (signal == SIGUSR2) {
      control.start_fault_camera = true;
    } else {
      stop = true;
    }
  });
  try {
    shapesense::RunRigSim(args, stop, &control);
  } catch (const shapesense::InputError& e) {
    std::cerr << "shapesense-rig-sim: error: " << e.what() << '\n';
    return shapesense::kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "shapesense-rig-sim: failed: " << e.what() << '\n';
    return shapesense::kExitFailed;
  }
  return 0;
}
