#include "services/shape/shape_service.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "libs/core/error.h"
#include "libs/mechanics/manipulator_options.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/message_convert.h"
#include "runtime/lcm/service_config.h"
#include "runtime/lcm/service_loop.h"

namespace shapesense {
namespace {

FrameSetKey KeyOfVoxels(const voxel_cloud_t& voxels) {
  return {voxels.trigger_seq >= 0 ? voxels.trigger_seq : -1, voxels.trigger_utime};
}

std::string NameOf(const voxel_cloud_t& voxels) {
  return voxels.trigger_seq >= 0 ? "frame-set " + std::to_string(voxels.trigger_seq)
                                 : "frame-set at " + std::to_string(voxels.trigger_utime) + " us";
}

std::optional<ConfigurationSetup> MatchingConfiguration(
    const ShapeServiceOptions& options, std::optional<ConfigurationSetup> configuration) {
  if (options.configuration.enabled != configuration.has_value()) {
    throw std::invalid_argument(
        "ShapeService: configuration.enabled and the configuration setup disagree");
  }
  return configuration;
}

bool AllFinite(const std::array<double, 3>& values) {
  return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

}  // namespace

std::string ShapeConfigurationOptions::Validate() const {
  if (enabled && manipulator.empty()) {
    return "manipulator: expected the manipulator model file (configuration is enabled), got "
           "nothing";
  }
  if (!AllFinite(base_position)) return "base_position: expected finite numbers";
  if (!AllFinite(base_rotation)) return "base_rotation: expected finite numbers";
  if (const std::string error = tapes.Validate(); !error.empty()) return "tapes." + error;
  if (const std::string error = sensing.Validate(); !error.empty()) return "sensing." + error;
  return {};
}

Pose3 ShapeConfigurationOptions::WorldFromBase() const {
  return PoseFromRotationVector(Vec3(base_rotation.data()), Vec3(base_position.data()));
}

std::optional<ConfigurationSetup> LoadConfigurationSetup(const ShapeServiceOptions& options) {
  const ShapeConfigurationOptions& section = options.configuration;
  if (!section.enabled) return std::nullopt;
  const ManipulatorOptions model =
      ParseManipulatorYaml(ReadTextFile(section.manipulator), section.manipulator);
  ConfigurationSetup setup;
  setup.geometry.rest = {model.proximal_length, model.distal_length};
  setup.geometry.world_from_base = section.WorldFromBase();
  setup.geometry.tapes = section.tapes;
  setup.options = section.sensing;
  if (const std::string error = setup.geometry.Validate(); !error.empty()) {
    throw InputError("configuration." + error + " (model file " + section.manipulator + ")");
  }
  return setup;
}

std::string ShapeServiceOptions::Validate() const {
  if (rig.empty()) return "rig: expected the rig file, got nothing";
  if (shape.refine_with_silhouettes && backgrounds.empty()) {
    return "backgrounds: expected the folder of backgrounds (needed by "
           "shape.refine_with_silhouettes), "
           "got nothing";
  }
  for (const auto& [section, error] :
       {std::pair{"silhouette.", silhouette.Validate()}, std::pair{"shape.", shape.Validate()},
        std::pair{"assembly.", assembly.Validate()},
        std::pair{"configuration.", configuration.Validate()}}) {
    if (!error.empty()) return section + error;
  }
  if (!(pairing_timeout_ms >= 1 && pairing_timeout_ms <= 60000)) {
    return "pairing_timeout_ms: expected 1-60000, got " + std::to_string(pairing_timeout_ms);
  }
  if (queue_capacity < 1 || queue_capacity > 100) {
    return "queue_capacity: expected 1-100, got " + std::to_string(queue_capacity);
  }
  return {};
}

ShapeService::ShapeService(const ShapeServiceOptions& options, RigSetup setup, LcmBus& bus,
                           std::optional<ConfigurationSetup> configuration)
    : options_(options),
      bus_(bus),
      stage_(setup.rig, std::move(setup.backgrounds), options.silhouette, options.shape,
             MatchingConfiguration(options, std::move(configuration))),
      pairing_timeout_us_(static_cast<int64_t>(std::llround(options.pairing_timeout_ms * 1e3))),
      assembler_(CameraNames(setup.rig), options.assembly),
      worker_(
          options.queue_capacity, status_, "voxel cloud",
          [](const Job& job) { return NameOf(job.voxels); },
          [this](Job& job) { MeasureAndPublish(job); }) {
  bus_.Subscribe<voxel_cloud_t>(
      channels::kVoxels, [this](voxel_cloud_t&& voxels, const std::string&, int64_t receive_utime) {
        OnVoxels(std::move(voxels), receive_utime);
      });
  if (stage_.wants_images()) {
    bus_.Subscribe<image_t>(channels::kImagePattern,
                            [this](image_t&& image, const std::string&, int64_t receive_utime) {
                              OnImage(std::move(image), receive_utime);
                            });
  }
}

void ShapeService::OnImage(image_t&& image, int64_t receive_utime) {
  if (const std::string error = ValidateImageMessage(image); !error.empty()) {
    status_.Rejected();
    status_.Note(error);
    return;
  }
  const std::string camera = image.camera;
  const int64_t dropped_before = assembler_.counters().DroppedSets();
  AssemblyResult result = assembler_.Add(std::move(image), receive_utime);
  CountAssemblyDrops(dropped_before);
  if (result.outcome == AssemblyOutcome::kCompleted) {
    OnFrameSet(std::move(*result.completed));
  } else if (IsRejection(result.outcome)) {
    status_.Rejected();
    status_.Note(camera + ": " + AssemblyOutcomeName(result.outcome));
  }
}

void ShapeService::CountAssemblyDrops(int64_t before) {
  if (assembler_.counters().DroppedSets() > before) status_.Note(assembler_.last_drop());
}

void ShapeService::OnFrameSet(FrameSet set) {
  const FrameSetKey key = KeyOf(set);
  const auto voxels =
      std::find_if(waiting_voxels_.begin(), waiting_voxels_.end(),
                   [&](const WaitingVoxels& w) { return KeyOfVoxels(w.voxels) == key; });
  if (voxels != waiting_voxels_.end()) {
    worker_.Push({std::move(voxels->voxels), std::move(set)});
    waiting_voxels_.erase(voxels);
    return;
  }
  // Usually the images come first: the carving service is still at work on them.
  const int64_t complete = set.complete_utime;
  waiting_images_.push_back({std::move(set), complete});
  while (waiting_images_.size() > 2 * static_cast<size_t>(options_.assembly.max_pending)) {
    waiting_images_.pop_front();
  }
}

void ShapeService::OnVoxels(voxel_cloud_t&& voxels, int64_t receive_utime) {
  status_.Received();
  // A full check is cheap (a few µs for a tube's thousands of voxels) and
  // keeps a malformed cloud from waiting for images it will never use.
  if (const std::string error = ValidateVoxelCloudMessage(voxels); !error.empty()) {
    status_.Rejected();
    status_.Note(NameOf(voxels) + ": " + error);
    return;
  }
  if (!stage_.wants_images()) {
    worker_.Push({std::move(voxels), std::nullopt});
    return;
  }
  const FrameSetKey key = KeyOfVoxels(voxels);
  const auto images = std::find_if(waiting_images_.begin(), waiting_images_.end(),
                                   [&](const WaitingImages& w) { return KeyOf(w.set) == key; });
  if (images != waiting_images_.end()) {
    worker_.Push({std::move(voxels), std::move(images->set)});
    waiting_images_.erase(images);
    return;
  }
  waiting_voxels_.push_back({std::move(voxels), receive_utime});
  if (waiting_voxels_.size() > static_cast<size_t>(options_.assembly.max_pending)) {
    worker_.Push({std::move(waiting_voxels_.front().voxels), std::nullopt});
    waiting_voxels_.pop_front();
  }
}

void ShapeService::Poll(int64_t now_utime) {
  const int64_t dropped_before = assembler_.counters().DroppedSets();
  assembler_.Expire(now_utime);
  CountAssemblyDrops(dropped_before);
  while (!waiting_voxels_.empty() &&
         now_utime - waiting_voxels_.front().receive_utime > pairing_timeout_us_) {
    worker_.Push({std::move(waiting_voxels_.front().voxels), std::nullopt});
    waiting_voxels_.pop_front();
  }
  std::erase_if(waiting_images_, [&](const WaitingImages& w) {
    return now_utime - w.complete_utime > pairing_timeout_us_;
  });
  status_.SetQueueDepth(worker_.depth());
  status_.MaybePublish(bus_, now_utime);
}

service_status_t ShapeService::Status(int64_t now_utime) {
  return status_.Snapshot(now_utime, bus_.Rejected());
}

void ShapeService::MeasureAndPublish(const Job& job) {
  const FrameSet* images = job.images ? &*job.images : nullptr;
  if (const std::string error = stage_.Process(job.voxels, images, &output_); !error.empty()) {
    status_.Rejected();
    status_.Note(NameOf(job.voxels) + ": " + error);
    return;
  }
  if (!output_.warning.empty()) status_.Error(NameOf(job.voxels) + ": " + output_.warning);
  output_.message.header.seq = shape_seq_++;
  output_.message.header.utime = NowUtime();
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
  ShapeServiceOptions options = LoadServiceOptions<ShapeServiceOptions>(
      args.config, {args.rig, args.backgrounds, args.lcm_url});
  options.configuration.manipulator =
      ResolveConfigPath(args.config, options.configuration.manipulator).string();
  return options;
}

service_status_t RunShapeService(const ServiceArgs& args, const std::atomic<bool>& stop,
                                 std::ostream& log) {
  const ShapeServiceOptions options = LoadShapeServiceOptions(args);
  const std::string backgrounds = options.shape.refine_with_silhouettes ? options.backgrounds : "";
  RigSetup setup = LoadRigSetup(options.rig, backgrounds);
  std::optional<ConfigurationSetup> configuration = LoadConfigurationSetup(options);
  LcmBus bus(options.lcm_url);
  ShapeService service(options, std::move(setup), bus, std::move(configuration));
  log << "shapesense-shape: running on "
      << (options.lcm_url.empty() ? "LCM's default" : options.lcm_url)
      << (options.shape.refine_with_silhouettes ? ", refining against the silhouettes" : "")
      << (options.configuration.enabled ? ", sensing the configuration q" : "") << '\n';
  RunBusLoop(bus, stop, args.duration_s, [&](int64_t now) { service.Poll(now); });
  return service.Status(NowUtime());
}

}  // namespace shapesense
