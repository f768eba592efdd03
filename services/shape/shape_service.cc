#include "services/shape/shape_service.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "libs/core/error.h"
#include "libs/mechanics/manipulator_options.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/service_config.h"
#include "runtime/lcm/service_loop.h"
#include "runtime/lcm/silhouette_message.h"
#include "runtime/lcm/voxel_cloud_message.h"
#include "runtime/process/systemd_notify.h"

namespace shapesense {
namespace {

// The frame-set a voxel cloud or silhouettes message comes from.
template <class Message>
FrameSetKey FrameSetOf(const Message& message) {
  return {message.trigger_seq >= 0 ? message.trigger_seq : -1, message.trigger_utime};
}

// Takes the waiting message of `key` out of `waiting`, if there is one.
template <class Message>
std::optional<Message> TakeWaiting(std::deque<Message>& waiting, const FrameSetKey& key) {
  const auto found = std::find_if(waiting.begin(), waiting.end(),
                                  [&](const Message& w) { return FrameSetOf(w.message) == key; });
  if (found == waiting.end()) return std::nullopt;
  std::optional<Message> taken(std::move(*found));
  waiting.erase(found);
  return taken;
}

template <class Message>
std::string NameOf(const Message& message) {
  return message.trigger_seq >= 0 ? "frame-set " + std::to_string(message.trigger_seq)
                                  : "frame-set at " + std::to_string(message.trigger_utime) + " us";
}

std::optional<ConfigurationSetup> MatchingConfiguration(
    const ShapeServiceOptions& options, std::optional<ConfigurationSetup> configuration) {
  if (options.configuration.enabled != configuration.has_value()) {
    throw std::invalid_argument(
        "ShapeService: configuration.enabled and the configuration setup disagree");
  }
  return configuration;
}

}  // namespace

std::string ShapeConfigurationOptions::Validate() const {
  if (enabled && manipulator.empty()) {
    return "manipulator: expected the manipulator model file (configuration is enabled), got "
           "nothing";
  }
  if (std::string error = base.Validate(); !error.empty()) return error;
  if (const std::string error = tapes.Validate(); !error.empty()) return "tapes." + error;
  if (const std::string error = sensing.Validate(); !error.empty()) return "sensing." + error;
  return {};
}

std::optional<ConfigurationSetup> LoadConfigurationSetup(const ShapeServiceOptions& options) {
  const ShapeConfigurationOptions& section = options.configuration;
  if (!section.enabled) return std::nullopt;
  const ManipulatorOptions model =
      ParseManipulatorYaml(ReadTextFile(section.manipulator), section.manipulator);
  ConfigurationSetup setup;
  setup.geometry.rest = {model.proximal_length, model.distal_length};
  setup.geometry.world_from_base = section.base.WorldFromBase();
  setup.geometry.tapes = section.tapes;
  setup.options = section.sensing;
  if (const std::string error = setup.geometry.Validate(); !error.empty()) {
    throw InputError("configuration." + error + " (model file " + section.manipulator + ")");
  }
  if (const std::string error = CheckBandWidth(setup.geometry, options.shape.band_width);
      !error.empty()) {
    throw InputError("shape." + error + " (tapes of configuration.tapes, model file " +
                     section.manipulator + ")");
  }
  return setup;
}

std::string ShapeServiceOptions::Validate() const {
  if (rig.empty()) return "rig: expected the rig file, got nothing";
  for (const auto& [section, error] : {std::pair{"shape.", shape.Validate()},
                                       std::pair{"configuration.", configuration.Validate()}}) {
    if (!error.empty()) return section + error;
  }
  if (!(pairing_timeout_ms >= 1 && pairing_timeout_ms <= 60000)) {
    return "pairing_timeout_ms: expected 1-60000, got " + std::to_string(pairing_timeout_ms);
  }
  if (max_waiting < 1 || max_waiting > 1000) {
    return "max_waiting: expected 1-1000, got " + std::to_string(max_waiting);
  }
  if (queue_capacity < 1 || queue_capacity > 100) {
    return "queue_capacity: expected 1-100, got " + std::to_string(queue_capacity);
  }
  return {};
}

ShapeService::ShapeService(const ShapeServiceOptions& options, const Rig& rig, LcmBus& bus,
                           std::optional<ConfigurationSetup> configuration)
    : options_(options),
      bus_(bus),
      stage_(rig, options.shape, MatchingConfiguration(options, std::move(configuration))),
      pairing_timeout_us_(static_cast<int64_t>(std::llround(options.pairing_timeout_ms * 1e3))),
      worker_(
          options.queue_capacity, status_, "voxel cloud",
          [](const Job& job) { return NameOf(job.voxels); },
          [this](Job& job) { MeasureAndPublish(job); }) {
  bus_.Subscribe<voxel_cloud_t>(
      channels::kVoxels, [this](voxel_cloud_t&& voxels, const std::string&, int64_t receive_utime) {
        OnVoxels(std::move(voxels), receive_utime);
      });
  if (stage_.wants_silhouettes()) {
    bus_.Subscribe<silhouettes_t>(
        channels::kSilhouettes,
        [this](silhouettes_t&& silhouettes, const std::string&, int64_t receive_utime) {
          OnSilhouettes(silhouettes, receive_utime);
        });
  }
}

void ShapeService::OnSilhouettes(const silhouettes_t& message, int64_t receive_utime) {
  // Checked and unpacked here, once (tens of µs), so that malformed
  // silhouettes are counted, not kept waiting for a cloud or silently forgotten.
  SilhouetteSet silhouettes;
  if (const std::string error = SilhouettesFromMessage(message, stage_.rig(), &silhouettes);
      !error.empty()) {
    status_.Rejected();
    status_.Note("silhouettes of " + NameOf(message) + ": " + error);
    return;
  }
  std::optional<Waiting<voxel_cloud_t>> voxels =
      TakeWaiting(waiting_voxels_, FrameSetOf(silhouettes));
  if (voxels) {
    worker_.Push({std::move(voxels->message), std::move(silhouettes), voxels->measured_utime});
    return;
  }
  // Usually the silhouettes come first: the carving service sends them first.
  waiting_silhouettes_.push_back({std::move(silhouettes), receive_utime});
  while (waiting_silhouettes_.size() > static_cast<size_t>(options_.max_waiting)) {
    waiting_silhouettes_.pop_front();
  }
}

void ShapeService::OnVoxels(voxel_cloud_t&& voxels, int64_t receive_utime) {
  status_.Received();
  // A full check is cheap (a few µs for a tube's thousands of voxels) and
  // keeps a malformed cloud from waiting for silhouettes it will never use.
  if (const std::string error = ValidateVoxelCloudMessage(voxels); !error.empty()) {
    status_.Rejected();
    status_.Note(NameOf(voxels) + ": " + error);
    return;
  }
  // Dated on this host's clock now, whatever the publisher's clock says.
  const int64_t measured = receive_utime - voxels.header.data_age_us;
  if (!stage_.wants_silhouettes()) {
    worker_.Push({std::move(voxels), std::nullopt, measured});
    return;
  }
  std::optional<Waiting<SilhouetteSet>> silhouettes =
      TakeWaiting(waiting_silhouettes_, FrameSetOf(voxels));
  if (silhouettes) {
    worker_.Push({std::move(voxels), std::move(silhouettes->message), measured});
    return;
  }
  waiting_voxels_.push_back({std::move(voxels), receive_utime, measured});
  if (waiting_voxels_.size() > static_cast<size_t>(options_.max_waiting)) {
    PushUnrefined(waiting_voxels_.front());
    waiting_voxels_.pop_front();
  }
}

void ShapeService::PushUnrefined(Waiting<voxel_cloud_t>& waiting) {
  worker_.Push({std::move(waiting.message), std::nullopt, waiting.measured_utime});
}

void ShapeService::Poll(int64_t now_utime) {
  while (!waiting_voxels_.empty() &&
         now_utime - waiting_voxels_.front().receive_utime > pairing_timeout_us_) {
    PushUnrefined(waiting_voxels_.front());
    waiting_voxels_.pop_front();
  }
  std::erase_if(waiting_silhouettes_, [&](const Waiting<SilhouetteSet>& w) {
    return now_utime - w.receive_utime > pairing_timeout_us_;
  });
  status_.SetQueueDepth(worker_.depth());
  status_.MaybePublish(bus_, now_utime);
}

service_status_t ShapeService::Status(int64_t now_utime) {
  return status_.Snapshot(now_utime, bus_.Rejected());
}

void ShapeService::MeasureAndPublish(const Job& job) {
  const SilhouetteSet* silhouettes = job.silhouettes ? &*job.silhouettes : nullptr;
  if (const std::string error = stage_.Process(job.voxels, silhouettes, &output_); !error.empty()) {
    status_.Rejected();
    status_.Note(NameOf(job.voxels) + ": " + error);
    return;
  }
  if (!output_.warning.empty()) status_.Error(NameOf(job.voxels) + ": " + output_.warning);
  output_.message.header.seq = shape_seq_++;
  output_.message.header.utime = NowUtime();
  output_.message.header.data_age_us =
      std::max<int64_t>(0, output_.message.header.utime - job.measured_utime);
  if (!bus_.Publish(channels::kShape, output_.message)) {
    status_.Error("could not publish on " + std::string(channels::kShape));
    return;
  }
  status_.Published();
  if (!output_.estimate.valid) {
    status_.Note(NameOf(job.voxels) + ": " + output_.estimate.error);
  } else if (stage_.senses_configuration() && !output_.configuration.valid) {
    status_.Note(NameOf(job.voxels) + ": no configuration: " + output_.configuration.reason);
  }
}

ShapeServiceOptions LoadShapeServiceOptions(const ServiceArgs& args) {
  if (!args.backgrounds.empty()) {
    throw InputError(
        "--backgrounds: the shape service uses none (the carving service sends it the "
        "silhouettes)");
  }
  ShapeServiceOptions options =
      LoadServiceOptions<ShapeServiceOptions>(args.config, {args.rig, {}, args.lcm_url});
  options.configuration.manipulator =
      ResolveConfigPath(args.config, options.configuration.manipulator).string();
  return options;
}

service_status_t RunShapeService(const ServiceArgs& args, const std::atomic<bool>& stop,
                                 std::ostream& log) {
  const ShapeServiceOptions options = LoadShapeServiceOptions(args);
  const RigSetup setup = LoadRigSetup(options.rig, {});
  std::optional<ConfigurationSetup> configuration = LoadConfigurationSetup(options);
  LcmBus bus(options.lcm_url);
  ShapeService service(options, setup.rig, bus, std::move(configuration));
  log << "shapesense-shape: running on "
      << (options.lcm_url.empty() ? "LCM's default" : options.lcm_url)
      << (options.shape.refine_with_silhouettes ? ", refining against the silhouettes" : "")
      << (options.configuration.enabled ? ", sensing the configuration q" : "") << '\n';
  SystemdNotifier supervisor;
  // The loop pings; the estimate runs on the worker, which must not hang either.
  supervisor.SetHealthCheck(
      [&] { return !service.WorkerBusyLongerThan(supervisor.watchdog_timeout() / 2); });
  supervisor.Ready("measuring shapes");
  RunBusLoop(
      bus, stop, args.duration_s, [&](int64_t now) { service.Poll(now); }, supervisor);
  return service.Status(NowUtime());
}

}  // namespace shapesense
