#include "clients/tools/demo/demo_plan.h"
#include "clients/tools/demo/demo_auth.h"

#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <sstream>

#include "runtime/lcm/image_buses.h"
#include "runtime/process/private_network.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

// Every program also gets a --duration well past the demo's end, so that
// none outlives a demo that was killed outright.
// The backgrounds are grabbed one camera after another: at least this fast.
constexpr double kBackgroundRateHz = 30.0;
// The nice value of the programs that stand for hardware (ProgramSpec::nice).
constexpr int kHardwareNice = -10;
// The web monitor is a view: on a machine short of CPU it yields to the pipeline.
constexpr int kViewerNice = 10;

std::string Backstop(const DemoSettings& settings) {
  return std::to_string(static_cast<int>(settings.duration_s) + 600);
}

// The shortest text that reads back as exactly `value`.
// A number for a program's command line: the shortest text that reads back
// as the same double (the message form, Number, keeps six digits).
std::string ExactNumber(double value) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof(text), value).ptr;
  return std::string(text, end);
}

std::string Program(const DemoSettings& settings, const std::string& name) {
  return (settings.bin_dir / name).string();
}

// --camera NAME=aravis:127.0.0.<i+1>, one per camera.
std::vector<std::string> GigECameraFlags(const DemoSettings& settings) {
  std::vector<std::string> flags;
  for (size_t i = 0; i < settings.camera_names.size(); ++i) {
    flags.push_back("--camera");
    flags.push_back(settings.camera_names[i] + "=aravis:" + LoopbackAddress(static_cast<int>(i)));
  }
  return flags;
}

std::string GigEAddresses(const DemoSettings& settings) {
  std::string addresses;
  for (size_t i = 0; i < settings.camera_names.size(); ++i) {
    if (i > 0) addresses += ',';
    addresses += LoopbackAddress(static_cast<int>(i));
  }
  return addresses;
}

ProgramSpec RigSim(const DemoSettings& settings, const DemoPlan& plan, bool backdrop_only) {
  ProgramSpec process{backdrop_only ? "rig-sim-backdrop" : "rig-sim",
                      {Program(settings, "shapesense-rig-sim"), "--rig", plan.rig.string(),
                       "--seed", std::to_string(settings.seed), "--ips", GigEAddresses(settings),
                       "--lcm-url", settings.lcm_url, "--duration", Backstop(settings)},
                      "rig-sim: ready",
                      "",
                      false,
                      kHardwareNice};
  if (backdrop_only) {
    process.argv.push_back("--backdrop-only");
  } else if (!settings.plant_config.empty()) {
    process.argv.push_back("--plant");
    process.argv.push_back(settings.plant_config.string());
  }
  return process;
}

// The cameras of the capture service: flags (GigE) or its config (simulated).
std::vector<std::string> CaptureCameras(const DemoSettings& settings, const DemoPlan& plan) {
  if (settings.cameras == DemoCameras::kGigE) return GigECameraFlags(settings);
  return {"--config", plan.capture_config.string()};
}

ProgramSpec CaptureBackground(const DemoSettings& settings, const DemoPlan& plan) {
  ProgramSpec process{
      "capture-background", {Program(settings, "shapesense-capture")}, "", "", true};
  for (const std::string& flag : CaptureCameras(settings, plan)) process.argv.push_back(flag);
  for (const std::string& arg :
       {std::string("--rate"), ExactNumber(std::max(settings.rate_hz, kBackgroundRateHz)),
        std::string("background"), std::string("--frames"),
        std::to_string(settings.background_frames), std::string("--out"),
        plan.backgrounds.string()}) {
    process.argv.push_back(arg);
  }
  return process;
}

ProgramSpec Capture(const DemoSettings& settings, const DemoPlan& plan) {
  ProgramSpec process{"capture",
                      {Program(settings, "shapesense-capture"), "--lcm-url", settings.lcm_url,
                       "--rate", ExactNumber(settings.rate_hz), "--duration", Backstop(settings)},
                      "",
                      "",
                      false,
                      kHardwareNice};
  for (const std::string& flag : CaptureCameras(settings, plan)) process.argv.push_back(flag);
  return process;
}

// The carving and shape services: defaults, the demo's rig, and the
// backgrounds for the carving service (the shape service gets silhouettes).
ProgramSpec Service(const DemoSettings& settings, const DemoPlan& plan, const std::string& name) {
  ProgramSpec process{name,
                      {Program(settings, "shapesense-" + name), "--lcm-url", settings.lcm_url,
                       "--rig", plan.rig.string(), "--duration", Backstop(settings)},
                      "",
                      name,
                      false};
  if (name == "carving") {
    process.argv.push_back("--backgrounds");
    process.argv.push_back(plan.backgrounds.string());
  }
  if (name == "shape" && !settings.shape_config.empty()) {
    process.argv.push_back("--config");
    process.argv.push_back(settings.shape_config.string());
  }
  return process;
}

// The web monitor on the socket the demo made in the host's network, the
// shape projected through the demo's rig, targets drawn from the shape
// service's config when it senses q.
ProgramSpec Monitor(const DemoSettings& settings, const DemoPlan& plan) {
  ProgramSpec process{"monitor",
                      {Program(settings, "shapesense-monitor"), "--lcm-url", settings.lcm_url,
                       "--calibration", plan.rig.string(), "--duration", Backstop(settings)},
                      "shapesense-monitor: serving",
                      "",
                      false};
  if (!settings.shape_config.empty()) {
    process.argv.push_back("--shape-config");
    process.argv.push_back(settings.shape_config.string());
  }
  process.listen_socket = settings.monitor_socket;
  // A view: when the CPU is short, the pipeline goes first (docs/monitor.md).
  process.nice = kViewerNice;
  return process;
}

ProgramSpec Logger(const DemoSettings& settings, const DemoPlan& plan) {
  ProgramSpec process{
      "lcm-logger",
      {settings.lcm_logger.string(), "--lcm-url=" + settings.lcm_url, "--force", plan.log.string()},
      "Opening log file",
      "",
      false};
  if (!settings.log_channels.empty()) {
    process.argv.insert(process.argv.begin() + 1, "--channel=" + settings.log_channels);
  }
  return process;
}

// The logger of camera k's images, on that camera's port.
ProgramSpec ImageLogger(const DemoSettings& settings, const DemoPlan& plan, size_t k) {
  return {"lcm-logger-" + settings.camera_names[k],
          {settings.lcm_logger.string(), "--lcm-url=" + ImageUrl(settings.lcm_url, k), "--force",
           plan.image_logs[k].string()},
          "Opening log file",
          "",
          false};
}

std::string SimulatedCaptureConfig(const DemoSettings& settings, const DemoPlan& plan) {
  std::ostringstream out;
  out << "# Written by `shapesense demo`: the virtual rig rendered inside the capture\n"
         "# service (config/capture.yaml documents every key).\ncameras:\n";
  for (const std::string& name : settings.camera_names) {
    out << "  - {name: " << name << ", backend: simulated}\n";
  }
  out << "trigger_rate_hz: " << ExactNumber(settings.rate_hz) << "\nrig: " << plan.rig.string()
      << "\nsimulation:\n  seed: " << settings.seed << "\n";
  return out.str();
}

}  // namespace

std::string CameraSourceName(DemoCameras cameras) {
  return cameras == DemoCameras::kGigE ? "gige" : "simulated";
}

ProgramSpec ControllerRun(const DemoSettings& settings, const fs::path& config,
                          const std::string& mode, const fs::path& log_dir) {
  ProgramSpec process{
      "controller-" + mode,
      {Program(settings, "shapesense-controller"), "--config", config.string(), "--mode", mode,
       "--targets", "stream", "--lcm-url", settings.lcm_url, "--log-csv",
       (log_dir / "controller_log.csv").string(), "--log-lcm",
       (log_dir / "controller_log.lcmlog").string(), "--duration", Backstop(settings)},
      "",
      "controller",
      false};
  AddAuthEnvironment(settings.auth, &process);
  return process;
}

DemoPlan MakeDemoPlan(const DemoSettings& settings) {
  DemoPlan plan;
  const fs::path work = settings.out / "setup";
  plan.rig = work / "rig.yaml";
  plan.backgrounds = work / "background";
  plan.log = settings.out / "pipeline.lcm";
  if (settings.log_channels.empty() && HasImageBuses(settings.lcm_url)) {
    for (const std::string& camera : settings.camera_names) {
      plan.image_logs.push_back(settings.out / ("images_" + camera + ".lcm"));
    }
  } else if (settings.log_channels.empty()) {
    plan.image_logs.push_back(plan.log);  // one bus: the images are in the run's log
  }
  plan.logs_dir = settings.out / "logs";
  plan.report = settings.out / "report.json";
  plan.replay_shapes = settings.out / "replay_shapes.jsonl";
  const bool gige = settings.cameras == DemoCameras::kGigE;
  if (!gige) {
    plan.capture_config = work / "capture.yaml";
    plan.capture_config_text = SimulatedCaptureConfig(settings, plan);
  }
  if (gige) plan.background.push_back(RigSim(settings, plan, true));
  plan.background.push_back(CaptureBackground(settings, plan));
  if (gige) plan.pipeline.push_back(RigSim(settings, plan, false));
  plan.pipeline.push_back(Logger(settings, plan));
  if (settings.monitor_socket >= 0) plan.pipeline.push_back(Monitor(settings, plan));
  for (size_t k = 0; HasImageBuses(settings.lcm_url) && k < plan.image_logs.size(); ++k) {
    plan.pipeline.push_back(ImageLogger(settings, plan, k));
  }
  plan.pipeline.push_back(Service(settings, plan, "carving"));
  plan.pipeline.push_back(Service(settings, plan, "shape"));
  plan.pipeline.push_back(Capture(settings, plan));
  for (std::vector<ProgramSpec>* phase : {&plan.background, &plan.pipeline}) {
    for (ProgramSpec& process : *phase) AddAuthEnvironment(settings.auth, &process);
  }
  return plan;
}

namespace {

std::string WhatToDo(const fs::path& program) {
  if (program.filename().string().starts_with("shapesense")) {
    return "build it: bash deploy/build.sh release (or ninja -C <build> " +
           program.filename().string() + ")";
  }
  return "install it: apt-get install liblcm-bin";
}

std::vector<const ProgramSpec*> AllProcesses(const DemoPlan& plan) {
  std::vector<const ProgramSpec*> all;
  for (const ProgramSpec& process : plan.background) all.push_back(&process);
  for (const ProgramSpec& process : plan.pipeline) all.push_back(&process);
  return all;
}

}  // namespace

std::vector<std::string> MissingPrograms(const DemoPlan& plan) {
  std::vector<std::string> missing;
  for (const ProgramSpec* process : AllProcesses(plan)) {
    const fs::path program = process->argv.front();
    const std::string line = program.string() + " is missing; " + WhatToDo(program);
    if (access(program.c_str(), X_OK) != 0 &&
        std::find(missing.begin(), missing.end(), line) == missing.end()) {
      missing.push_back(line);
    }
  }
  return missing;
}

}  // namespace shapesense
