#pragma once

// The live demo's programs and their command lines, worked out before
// anything starts: a pure function of the settings, so that what the demo
// runs can be read (and tested) without running it.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "runtime/lcm/bus_auth.h"
#include "runtime/process/process_group.h"

namespace shapesense {

// Where the camera images come from.
enum class DemoCameras {
  kGigE,       // the rig-sim's fake GigE Vision cameras on 127.0.0.x, read over Aravis
  kSimulated,  // rendered inside the capture process (no GigE, no rig-sim)
};

std::string CameraSourceName(DemoCameras cameras);  // "gige" | "simulated"

// LCM's default URL (multicast that never leaves the host: ttl=0), with the
// larger socket buffer that receivers of images need (docs/capture.md). In a
// private network namespace it stays inside the namespace.
inline constexpr const char* kDemoLcmUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

struct DemoSettings {
  std::filesystem::path bin_dir;     // shapesense-rig-sim, -capture, -carving, -shape
  std::filesystem::path lcm_logger;  // lcm-logger (liblcm-bin)
  std::filesystem::path out;         // everything the demo writes
  DemoCameras cameras = DemoCameras::kGigE;
  std::vector<std::string> camera_names;  // the rig's, in order
  std::string lcm_url = kDemoLcmUrl;      // every program's
  double rate_hz = 30.0;                  // software trigger rate
  double duration_s = 20.0;               // of the measured run
  uint32_t seed = 7;                      // pixel noise
  int background_frames = 15;             // per camera, for the median
  // Plant mode (the closed-loop experiment): the rig-sim's --plant file and
  // the shape service's --config (which senses q); empty: the trajectory and
  // the shape service's defaults.
  std::filesystem::path plant_config;
  std::filesystem::path shape_config;
  // The channels lcm-logger records (a regex; empty: all). Camera images at
  // 30 Hz are about 85 MB per second of run.
  std::string log_channels;
  // How every program authenticates (demo_auth.h): the run's key.
  AuthOptions auth;
  // The web monitor's listening socket, made in the host's network before
  // the demo entered its namespace (listening_socket.h); -1: no monitor.
  int monitor_socket = -1;
};

// Everything but the camera images, the silhouettes and the voxels: what a
// controller run needs to be studied again (shapes with q, truth, targets,
// commands, actuator and plant states, e-stops, status), a few MB a minute.
inline constexpr const char* kControlChannels =
    "SHAPESENSE_(SHAPE|TRUTH|TARGET|ESTOP|TENDON_.*|PLANT_.*|STATUS_.*)";

struct DemoPlan {
  std::filesystem::path rig;             // written by the demo before anything starts
  std::filesystem::path backgrounds;     // <camera>.png, made by the first phase
  std::filesystem::path capture_config;  // simulated cameras only (empty otherwise)
  std::string capture_config_text;
  std::filesystem::path log;  // the LCM log of the run (every channel but the images)
  // The cameras' images, one log per camera's port (runtime/lcm/image_buses.h);
  // none when settings.log_channels picks channels.
  std::vector<std::filesystem::path> image_logs;
  std::filesystem::path logs_dir;  // one <name>.log per program
  std::filesystem::path report;
  std::filesystem::path replay_shapes;  // the replay's JSON lines
  // Phase 1, the backgrounds: started in order; the last runs to its end.
  std::vector<ProgramSpec> background;
  // Phase 2, the live pipeline, in start order; stopped in the reverse order
  // (capture first, so that the last frame-sets drain through before the
  // services and the logger stop).
  std::vector<ProgramSpec> pipeline;
};

DemoPlan MakeDemoPlan(const DemoSettings& settings);

// The programs of `plan` that are missing or not executable, each with what
// to do about it; empty when all are there.
std::vector<std::string> MissingPrograms(const DemoPlan& plan);

// One run of shapesense-controller in the closed-loop experiment: `config`
// (config/controller_client.yaml) in `mode`, its targets streamed, its logs
// in `log_dir`. Up once its status ("controller") has arrived.
ProgramSpec ControllerRun(const DemoSettings& settings, const std::filesystem::path& config,
                          const std::string& mode, const std::filesystem::path& log_dir);

}  // namespace shapesense
