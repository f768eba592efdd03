#include "clients/tools/demo_command.h"
#include "runtime/process/signal_thread.h"

#include <unistd.h>

#include <iostream>
#include <memory>

#include "clients/tools/demo/closed_loop_experiment.h"
#include "clients/tools/demo/demo_hosts.h"
#include "clients/tools/demo/live_demo.h"
#include "clients/tools/demo/offline_demo.h"
#include "libs/core/error.h"
#include "runtime/lcm/service_loop.h"
#include "runtime/process/listening_socket.h"
#include "runtime/process/private_network.h"

namespace shapesense {
namespace {

// Loopback addresses the private namespace gets: one per fake camera, and spare.
constexpr int kLoopbackAddresses = 8;

struct DemoCommandArgs {
  LiveDemoArgs live;
  ExperimentArgs experiment;
  bool pipeline = false;
  bool offline = false;
  int frames = 16;
  double voxel_size = 1.0;
  std::string network = "auto";
  std::string cameras = "auto";
  bool no_replay = false;
  int hosts = 1;
  double camera_clock_offset_ms = 0.0;
  bool faults = false;
  bool insecure = false;
  bool attacker = false;
  std::string monitor = "127.0.0.1:8080";
  bool monitor_given = false;
};

// The web monitor's socket, made here in the host's network before the demo
// moves into a namespace of its own, so that a browser on this machine
// reaches the monitor inside it (docs/monitor.md). The default port, when
// taken, gives way to a free one; a port asked for must be had.
int OpenMonitorSocket(const DemoCommandArgs& args) {
  if (args.monitor == "off") return -1;
  try {
    return OpenListeningSocket(args.monitor);
  } catch (const std::runtime_error& e) {
    if (args.monitor_given) throw InputError(std::string("--monitor: ") + e.what());
    std::cout << "demo: " << e.what() << "; the monitor takes a free port instead\n";
    return OpenListeningSocket(args.monitor.substr(0, args.monitor.rfind(':')) + ":0");
  }
}

NetworkMode ParseNetwork(const std::string& network) {
  if (network == "private") return NetworkMode::kPrivate;
  if (network == "current") return NetworkMode::kCurrent;
  return NetworkMode::kAuto;
}

// GigE needs the namespace's 127.0.0.x addresses; without one, the capture
// service renders the cameras itself.
DemoCameras ChooseCameras(const DemoCommandArgs& args, const NetworkChoice& network) {
  if (args.cameras == "simulated") return DemoCameras::kSimulated;
  if (args.cameras == "gige") {
    if (!network.private_namespace && args.network == "auto") {
      throw InputError("--cameras gige: needs a private network namespace, and " + network.why_not);
    }
    return DemoCameras::kGigE;
  }
  return network.private_namespace ? DemoCameras::kGigE : DemoCameras::kSimulated;
}

void RunOffline(const DemoCommandArgs& args) {
  OfflineDemoArgs offline;
  offline.out = args.live.out;
  offline.frames = args.frames;
  offline.seed = args.live.seed;
  offline.voxel_size = args.voxel_size;
  RunOfflineDemo(offline, std::cout);
}

void RunLive(DemoCommandArgs& args) {
  args.live.monitor_socket = OpenMonitorSocket(args);
  // First, while this process has a single thread.
  const NetworkChoice network = EnterNetwork(ParseNetwork(args.network), kLoopbackAddresses);
  const std::atomic<bool>& stop = StopFlagOnSignals();
  LiveDemoArgs& live = args.live;
  live.cameras = ChooseCameras(args, network);
  live.network = network.private_namespace ? "private network namespace"
                                           : "this host's (" + network.why_not + ")";
  if (!network.private_namespace) {
    std::cout << "demo: no private network namespace: " << network.why_not
              << ".\n      Running on this host's network with LCM's host-only default (udpm, "
                 "ttl=0)"
              << (live.cameras == DemoCameras::kSimulated
                      ? ", the cameras rendered inside the capture service (no GigE)"
                      : "")
              << ".\n";
  }
  live.replay = !args.no_replay;
  live.progress = isatty(STDOUT_FILENO) ? DemoProgress::kTerminal : DemoProgress::kLines;
  const LiveDemoReport report = RunLiveDemo(live, stop, std::cout);
  if (report.interrupted) throw CLI::RuntimeError(130);
}

// The experiment's options from the command's, on `network`.
ExperimentArgs& ExperimentOptions(DemoCommandArgs& args, const std::string& network) {
  ExperimentArgs& experiment = args.experiment;
  experiment.out = args.live.out;
  experiment.rate_hz = args.live.rate_hz;
  experiment.seed = args.live.seed;
  experiment.network = network;
  return experiment;
}

// The plant lives in the rig-sim, whose cameras need the namespace's addresses.
void RunExperiment(DemoCommandArgs& args) {
  args.experiment.monitor_socket = OpenMonitorSocket(args);
  const NetworkChoice network = EnterNetwork(ParseNetwork(args.network), kLoopbackAddresses);
  const std::atomic<bool>& stop = StopFlagOnSignals();
  if (!network.private_namespace) {
    throw InputError(
        "the closed-loop experiment runs the virtual rig's GigE cameras on "
        "127.0.0.x in a private network namespace, and " +
        network.why_not +
        " (run as root, or allow unprivileged user namespaces; `shapesense demo "
        "--pipeline` runs the sensing alone without one)");
  }
  ExperimentArgs& experiment = ExperimentOptions(args, "private network namespace");
  const ExperimentReport report = RunClosedLoopExperiment(experiment, stop, std::cout);
  if (report.interrupted) throw CLI::RuntimeError(130);
}

// Three hosts (network namespaces on a bridge) inside the private namespace,
// made before any thread starts (each `ip` is a fork).
void RunExperimentOnHosts(DemoCommandArgs& args) {
  args.experiment.monitor_socket = OpenMonitorSocket(args);
  const NetworkChoice network = EnterNetwork(NetworkMode::kPrivate, kLoopbackAddresses);
  if (!network.private_namespace) throw InputError("--hosts 3: " + network.why_not);
  const VirtualHosts hosts(DemoHostSpecs(args.camera_clock_offset_ms, kLoopbackAddresses));
  const std::atomic<bool>& stop = StopFlagOnSignals();
  ExperimentArgs& experiment =
      ExperimentOptions(args, "three hosts (network namespaces on a bridge)");
  experiment.hosts = &hosts;
  if (args.faults) experiment.faults = StandardFaults(experiment.targets.count);
  const ExperimentReport report = RunClosedLoopExperiment(experiment, stop, std::cout);
  if (report.interrupted) throw CLI::RuntimeError(130);
}

}  // namespace

void AddDemoCommand(CLI::App& app) {
  auto args = std::make_shared<DemoCommandArgs>();
  CLI::App* command = app.add_subcommand(
      "demo",
      "The closed-loop experiment on the virtual rig: the live pipeline as separate programs "
      "over LCM, the controller driving the rig's plant through targets in open loop, then "
      "closed loop on the sensed shape; a table, a plot and report.json of the tip errors. "
      "--pipeline: the sensing alone, scored against the rig's truth, logged and replayed");
  command->add_option("--out", args->live.out, "output folder")->capture_default_str();
  command->add_option("--duration", args->live.duration_s, "--pipeline: seconds to measure")
      ->capture_default_str();
  command->add_option("--targets", args->experiment.targets.count, "number of targets")
      ->capture_default_str();
  command->add_option("--hold", args->experiment.targets.hold_s, "seconds each target is held")
      ->capture_default_str();
  command
      ->add_option("--window", args->experiment.window_s,
                   "steady state: the last this many seconds of each hold")
      ->capture_default_str();
  command->add_option("--modes", args->experiment.modes, "controller modes, one run each")
      ->delimiter(',')
      ->capture_default_str();
  command->add_option("--config-dir", args->experiment.config_dir,
                      "the repository's config/ (default: found beside the build)");
  command->add_option("--rate", args->live.rate_hz, "camera trigger rate, Hz")
      ->capture_default_str();
  command->add_option("--seed", args->live.seed, "seed of the rig and the noise")
      ->capture_default_str();
  command
      ->add_option("--network", args->network,
                   "auto: a private network namespace where possible, else this host's; "
                   "private: the namespace or fail; current: this process's network")
      ->check(CLI::IsMember({"auto", "private", "current"}))
      ->capture_default_str();
  command
      ->add_option("--cameras", args->cameras,
                   "gige: the rig-sim's fake GigE Vision cameras over Aravis; simulated: "
                   "rendered inside the capture service; auto: gige in a private namespace")
      ->check(CLI::IsMember({"auto", "gige", "simulated"}))
      ->capture_default_str();
  command
      ->add_option("--hosts", args->hosts,
                   "1: every program on one network; 3: camera, control and operator hosts "
                   "(network namespaces on a bridge; docs/rig.md)")
      ->check(CLI::IsMember({1, 3}))
      ->capture_default_str();
  command
      ->add_option("--camera-clock-offset-ms", args->camera_clock_offset_ms,
                   "--hosts 3: the camera host's clock this far off, ms (test-only)")
      ->capture_default_str();
  command->add_flag("--faults", args->faults,
                    "--hosts 3: in the last run, pull the control host's link for 2 s, kill "
                    "the shape service (restarted), restart the logger");
  command->add_flag("--insecure", args->insecure,
                    "run without message authentication (loudly): any process on the rig "
                    "network could move the tendons (docs/security.md)");
  command->add_flag("--attacker", args->attacker,
                    "the closed-loop experiment with an attacker on the rig network: forged, "
                    "bit-flipped and replayed targets, shapes and plant commands; report.json "
                    "says how many were sent, rejected and accepted");
  command->add_flag("--pipeline", args->pipeline,
                    "the live sensing pipeline alone (no controller), scored, logged, replayed");
  command->add_flag("--no-replay", args->no_replay, "--pipeline: do not replay the log");
  command->add_flag("--offline", args->offline,
                    "the old demo instead: render a sequence, measure it in this process, "
                    "write overlay pictures (no LCM)");
  command->add_option("--frames", args->frames, "--offline: frames to render")
      ->capture_default_str();
  command->add_option("--voxel-size", args->voxel_size, "--offline: voxel edge, mm")
      ->capture_default_str();
  command
      ->add_option("--monitor", args->monitor,
                   "the web monitor's HOST:PORT on this machine's network, or off")
      ->capture_default_str();
  command->callback([args, command] {
    args->monitor_given = command->count("--monitor") > 0;
    if (args->hosts != 3 && (args->faults || args->camera_clock_offset_ms != 0.0)) {
      throw InputError("--faults and --camera-clock-offset-ms need --hosts 3");
    }
    if (args->attacker && (args->pipeline || args->offline)) {
      throw InputError(
          "--attacker runs with the closed-loop experiment, not --pipeline or --offline");
    }
    args->live.auth.insecure = args->insecure;
    args->experiment.auth.insecure = args->insecure;
    args->experiment.attacker = args->attacker;
    if (args->offline) {
      RunOffline(*args);
    } else if (args->pipeline) {
      RunLive(*args);
    } else if (args->hosts == 3) {
      RunExperimentOnHosts(*args);
    } else {
      RunExperiment(*args);
    }
  });
}

}  // namespace shapesense
