#include "services/rig_sim/rig_sim.h"

#include <chrono>
#include <iostream>
#include <memory>
#include <optional>
#include <thread>

#include "libs/camera/rig_yaml.h"
#include "libs/core/error.h"
#include "libs/sim/scene_generators.h"
#include "runtime/config_file.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/lcm/service_status.h"
#include "runtime/lcm/truth_message.h"
#include "runtime/process/systemd_notify.h"
#include "services/rig_sim/fake_camera_server.h"

namespace shapesense {
namespace {

constexpr auto kLoopPeriod = std::chrono::milliseconds(2);

struct Setup {
  Rig rig;
  TrajectoryOptions trajectory;
  std::vector<std::string> addresses;
  std::vector<Outage> outages;
  int fault_camera = 0;
  std::optional<PlantWorldSetup> plant;
};

Rig LoadRig(const RigSimArgs& args) {
  if (!args.rig_path.empty()) return ParseRigYaml(ReadTextFile(args.rig_path), args.rig_path);
  SyntheticRigOptions options;
  options.seed = args.seed;
  return MakeSyntheticRig(options);
}

int CameraIndex(const std::string& name, const Rig& rig, const std::string& what) {
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    if (rig.cameras[i].name == name || std::to_string(i) == name) return static_cast<int>(i);
  }
  throw InputError(what + ": no camera '" + name + "' in the rig");
}

std::vector<std::string> Addresses(const RigSimArgs& args, const Rig& rig) {
  if (args.ips.empty()) {
    std::vector<std::string> addresses;
    for (size_t i = 0; i < rig.cameras.size(); ++i)
      addresses.push_back("127.0.0." + std::to_string(i + 1));
    return addresses;
  }
  if (args.ips.size() != rig.cameras.size()) {
    throw InputError("--ips: expected one address per camera (" +
                     std::to_string(rig.cameras.size()) + "), got " +
                     std::to_string(args.ips.size()));
  }
  return args.ips;
}

Setup LoadSetup(const RigSimArgs& args) {
  if (!(args.packet_loss >= 0.0 && args.packet_loss <= 1.0)) {
    throw InputError("--packet-loss: expected a fraction 0-1, got " +
                     std::to_string(args.packet_loss));
  }
  if (!(args.faults.answer_delay_max_ms >= 0.0 && args.faults.answer_delay_max_ms <= 1000.0)) {
    throw InputError("--answer-delay-ms: expected 0-1000 ms, got " +
                     std::to_string(args.faults.answer_delay_max_ms));
  }
  if (!(args.faults.miss_ratio >= 0.0 && args.faults.miss_ratio < 1.0)) {
    throw InputError("--miss-ratio: expected a fraction in [0, 1), got " +
                     std::to_string(args.faults.miss_ratio));
  }
  if (!(args.faults.repeat_ratio >= 0.0 && args.faults.repeat_ratio < 1.0)) {
    throw InputError("--repeat-ratio: expected a fraction in [0, 1), got " +
                     std::to_string(args.faults.repeat_ratio));
  }
  if (!(args.duration_s >= 0.0)) {
    throw InputError("--duration: expected seconds >= 0, got " + std::to_string(args.duration_s));
  }
  Setup setup{LoadRig(args), LoadOptionsFile<TrajectoryOptions>(args.trajectory_path), {}, {}, 0,
              std::nullopt};
  if (!args.plant_path.empty()) setup.plant = LoadPlantWorldSetup(args.plant_path);
  if (const std::string error = setup.rig.Validate(); !error.empty()) {
    throw InputError((args.rig_path.empty() ? "synthetic rig" : args.rig_path) + ": " + error);
  }
  setup.addresses = Addresses(args, setup.rig);
  if (!args.write_rig_path.empty()) {
    WriteFileAtomically(args.write_rig_path, FormatRigYaml(setup.rig));
  }
  for (const std::string& spec : args.outages) {
    setup.outages.push_back(ParseOutage(spec, setup.rig));
  }
  setup.fault_camera = args.fault_camera.empty()
                           ? static_cast<int>(setup.rig.cameras.size()) - 1
                           : CameraIndex(args.fault_camera, setup.rig, "--fault-camera");
  return setup;
}

// The truth at one of the reference camera's exposures: the trajectory's, or
// in plant mode the plant's (with q). Its trigger_seq is the exposure's frame
// id, its trigger_utime the exposure's time: every frame-set's images are
// exposed within a few milliseconds after their trigger, so the truth of a
// set is the one that follows its trigger time most closely.
shape_t TruthOf(const CameraExposure& exposure, const PlantWorld* plant, int64_t seq) {
  if (plant != nullptr) {
    return plant->TruthMessage(*exposure.scene, exposure.frame_id, exposure.utime, seq, NowUtime());
  }
  return FrameSetTruth(*exposure.scene, exposure.pose, exposure.frame_id, exposure.utime, seq,
                       NowUtime());
}

void PublishTruth(FakeCameraServer& server, LcmBus& bus, ServiceStatus& status, int64_t* seq,
                  bool backdrop_only, const PlantWorld* plant) {
  for (const CameraExposure& exposure : server.TakeReferenceExposures()) {
    if (backdrop_only) continue;  // nothing to measure
    const shape_t truth = TruthOf(exposure, plant, (*seq)++);
    if (bus.Publish(channels::kTruth, truth)) {
      status.Published();
    } else {
      status.Error("cannot publish the truth of exposure " + std::to_string(exposure.frame_id));
    }
  }
}

void SetCamera(FakeCameraServer& server, const Rig& rig, int camera, bool on,
               const std::string& why) {
  if (server.Running(camera) == on) return;
  try {
    if (on) {
      server.Start(camera);
    } else {
      server.Stop(camera);
    }
  } catch (const std::exception& e) {  // the address may still be held: tried again next loop
    std::cerr << e.what() << std::endl;
    return;
  }
  std::cout << "rig-sim: " << rig.cameras[static_cast<size_t>(camera)].name
            << (on ? " back on the network" : " off the network") << " (" << why << ")"
            << std::endl;
}

// Each outage stops its camera at its start and starts it at its end.
void ApplyOutages(FakeCameraServer& server, const Setup& setup, double t) {
  for (const Outage& outage : setup.outages) {
    const bool inside = t >= outage.start_s && t < outage.start_s + outage.duration_s;
    const bool just_over =
        t >= outage.start_s + outage.duration_s && t < outage.start_s + outage.duration_s + 0.5;
    if (inside) SetCamera(server, setup.rig, outage.camera, false, "scheduled outage");
    if (just_over) SetCamera(server, setup.rig, outage.camera, true, "end of the outage");
  }
}

void ApplyControl(FakeCameraServer& server, const Setup& setup, RigSimControl* control) {
  if (control == nullptr) return;
  if (control->stop_fault_camera.exchange(false)) {
    SetCamera(server, setup.rig, setup.fault_camera, false, "requested");
  }
  if (control->start_fault_camera.exchange(false)) {
    SetCamera(server, setup.rig, setup.fault_camera, true, "requested");
  }
}

// Images served count as received; images it could not make, as errors.
void CountImages(const FakeCameraServer& server, ServiceStatus& status, int64_t* images,
                 int64_t* errors) {
  status.Received(server.images_served() - *images);
  *images = server.images_served();
  if (server.errors() > *errors) {
    *errors = server.errors();
    status.Error(std::to_string(*errors) + " images could not be made (unknown pixel format?)");
  }
}

// Plant mode: the plant's commands in, its state out, through the link.
class PlantMode {
 public:
  PlantMode(const PlantWorldSetup& setup, LcmBus& bus)
      : world_(std::make_shared<PlantWorld>(setup)), link_(bus, *world_) {
    std::cout << "rig-sim: plant mode: " << world_->num_tendons() << " tendons on "
              << channels::kPlantCommand << ", state on " << channels::kPlantState << std::endl;
  }
  const std::shared_ptr<PlantWorld>& world() const { return world_; }

  // Hands over what came, advances the plant and publishes its state when due.
  void Poll(LcmBus& bus, ServiceStatus& status, int64_t now) {
    // At most a loop's worth of messages: the callbacks only queue.
    for (int i = 0; i < kMaxMessagesPerPoll && bus.Handle(0) > 0; ++i) {
    }
    const PlantPoll poll = link_.Poll(now);
    status.Received(poll.accepted);
    if (!poll.rejections.empty()) {
      status.Rejected(static_cast<int64_t>(poll.rejections.size()));
      status.Note("plant command rejected: " + poll.rejections.back());
    }
    if (poll.dropped > 0) status.Dropped(poll.dropped);
  }

 private:
  static constexpr int kMaxMessagesPerPoll = 64;
  std::shared_ptr<PlantWorld> world_;
  PlantLink link_;
};

void StartCameras(FakeCameraServer& server, const Setup& setup) {
  for (int i = 0; i < server.num_cameras(); ++i) {
    server.Start(i);
    std::cout << "rig-sim: " << setup.rig.cameras[static_cast<size_t>(i)].name << " serves on "
              << setup.addresses[static_cast<size_t>(i)] << " as Aravis-Fake-" << server.serial(i)
              << std::endl;
  }
  std::cout << "rig-sim: ready" << std::endl;
}

}  // namespace

Outage ParseOutage(const std::string& spec, const Rig& rig) {
  const size_t first = spec.find(':');
  const size_t second = first == std::string::npos ? first : spec.find(':', first + 1);
  const std::string what = "--outage '" + spec + "'";
  if (second == std::string::npos) throw InputError(what + ": expected CAMERA:START_S:DURATION_S");
  Outage outage;
  outage.camera = CameraIndex(spec.substr(0, first), rig, what);
  try {
    outage.start_s = std::stod(spec.substr(first + 1, second - first - 1));
    outage.duration_s = std::stod(spec.substr(second + 1));
  } catch (const std::exception&) {
    throw InputError(what + ": expected numbers of seconds for START_S and DURATION_S");
  }
  if (!(outage.start_s >= 0.0 && outage.duration_s > 0.0)) {
    throw InputError(what + ": expected START_S >= 0 and DURATION_S > 0");
  }
  return outage;
}

void RunRigSim(const RigSimArgs& args, const std::atomic<bool>& stop, RigSimControl* control) {
  const Setup setup = LoadSetup(args);
  LcmBus bus(args.lcm_url);
  ServiceStatus status("rig_sim");
  const int64_t start_utime = NowUtime();
  std::optional<PlantMode> plant;
  if (setup.plant) plant.emplace(*setup.plant, bus);
  const PlantWorld* plant_world = plant ? plant->world().get() : nullptr;
  FakeCameraServer server(setup.rig, setup.trajectory, setup.addresses, args.seed, start_utime);
  server.SetPacketLoss(args.packet_loss);
  server.SetBackdropOnly(args.backdrop_only);
  CameraFaults faults = args.faults;
  faults.seed = args.seed + 1;
  server.SetFaults(faults);
  if (plant) server.SetPlant(plant->world());
  StartCameras(server, setup);
  SystemdNotifier supervisor;
  supervisor.Ready("serving " + std::to_string(server.num_cameras()) + " cameras");
  int64_t truth_seq = 0, images = 0, errors = 0;
  while (!stop) {
    supervisor.Watchdog();  // from this loop: if it hangs, systemd restarts the rig
    const int64_t now = NowUtime();
    const double t = static_cast<double>(now - start_utime) * 1e-6;
    if (args.duration_s > 0.0 && t >= args.duration_s) break;
    if (plant) plant->Poll(bus, status, now);
    PublishTruth(server, bus, status, &truth_seq, args.backdrop_only, plant_world);
    ApplyOutages(server, setup, t);
    ApplyControl(server, setup, control);
    CountImages(server, status, &images, &errors);
    status.MaybePublish(bus, now);
    std::this_thread::sleep_for(kLoopPeriod);
  }
  supervisor.Stopping();
  PublishTruth(server, bus, status, &truth_seq, args.backdrop_only, plant_world);
}

}  // namespace shapesense
