#include "services/carving/carving_service.h"

#include <algorithm>

#include "libs/core/error.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/image_codec.h"
#include "runtime/lcm/service_config.h"
#include "runtime/lcm/service_loop.h"
#include "runtime/lcm/wire_check.h"
#include "runtime/process/systemd_notify.h"

namespace shapesense {
namespace {

std::string FrameSetName(const FrameSet& set) {
  return set.trigger_seq >= 0 ? "frame-set " + std::to_string(set.trigger_seq)
                              : "frame-set at " + std::to_string(set.trigger_utime) + " us";
}

}  // namespace

std::string CarvingServiceOptions::Validate() const {
  if (rig.empty()) return "rig: expected the rig file, got nothing";
  if (backgrounds.empty()) return "backgrounds: expected the folder of backgrounds, got nothing";
  for (const auto& [section, error] :
       {std::pair{"silhouette.", silhouette.Validate()}, std::pair{"carving.", carving.Validate()},
        std::pair{"assembly.", assembly.Validate()}}) {
    if (!error.empty()) return section + error;
  }
  if (queue_capacity < 1 || queue_capacity > 100) {
    return "queue_capacity: expected 1-100, got " + std::to_string(queue_capacity);
  }
  if (!(silhouette_rate_hz >= 0 && silhouette_rate_hz <= 100)) {
    return "silhouette_rate_hz: expected 0-100, got " + std::to_string(silhouette_rate_hz);
  }
  return {};
}

CarvingService::CarvingService(const CarvingServiceOptions& options, RigSetup setup, LcmBus& bus,
                               CarvingServiceHooks hooks)
    : options_(options),
      bus_(bus),
      image_buses_(bus, setup.rig.cameras.size()),
      hooks_(std::move(hooks)),
      stage_(setup.rig, std::move(setup.backgrounds), options.silhouette, options.carving),
      assembler_(CameraNames(setup.rig), options.assembly),
      // A view for every image the pending sets can hold, and one more.
      prepared_(static_cast<size_t>(options.assembly.max_pending + 1) *
                stage_.rig().cameras.size()),
      // The views of the sets the queue and the worker hold, and one set more.
      view_pool_(static_cast<size_t>(options.queue_capacity + 2) * stage_.rig().cameras.size()),
      worker_(
          options.queue_capacity, status_, "frame-set",
          [](const CarvingJob& job) { return FrameSetName(job.set); },
          [this](CarvingJob& job) {
            if (hooks_.before_carving) hooks_.before_carving(job.set);
            CarveAndPublish(job);
          }) {
  SubscribeToImages(CameraNames(stage_.rig()));
}

void CarvingService::SubscribeToImages(const std::vector<std::string>& cameras) {
  if (!HasImageBuses(bus_.local_url())) {
    bus_.SubscribeRaw(
        channels::kImagePattern,
        [this](std::span<const uint8_t> buffer, const std::string& channel, int64_t receive_utime) {
          return OnImageBytes(buffer, channel, "", receive_utime);
        });
    return;
  }
  for (size_t k = 0; k < cameras.size(); ++k) {
    image_buses_.ForCamera(k).SubscribeRaw(
        channels::kImagePattern,
        [this, camera = cameras[k]](std::span<const uint8_t> buffer, const std::string& channel,
                                    int64_t receive_utime) {
          return OnImageBytes(buffer, channel, camera, receive_utime);
        });
  }
}

std::vector<LcmBus*> CarvingService::Buses() const {
  std::vector<LcmBus*> buses{&bus_};
  for (LcmBus* bus : image_buses_.Opened()) buses.push_back(bus);
  return buses;
}

std::string CarvingService::OnImageBytes(std::span<const uint8_t> buffer,
                                         const std::string& channel,
                                         const std::string& camera_of_bus, int64_t receive_utime) {
  image_t image;
  std::span<const uint8_t> bytes;
  if (std::string why = DecodeImageFields(buffer.data(), buffer.size(), &image, &bytes);
      !why.empty()) {
    return why;
  }
  OnImage(std::move(image), bytes, channel, camera_of_bus, receive_utime);
  return {};
}

bool CarvingService::AcceptableImage(const image_t& image, std::span<const uint8_t> bytes,
                                     const std::string& channel, const std::string& camera_of_bus) {
  std::string refusal = ValidateImageMessage(image, bytes);
  // Each camera's port carries that camera's images only.
  if (refusal.empty() && !camera_of_bus.empty() && image.camera != camera_of_bus) {
    refusal = channel + ": image of camera '" + image.camera + "' on camera '" + camera_of_bus +
              "''s port";
  }
  // A camera speaks for itself only: an image naming another camera than
  // its channel's could join that camera's frame-sets.
  if (refusal.empty() && channel != channels::Image(image.camera)) {
    refusal = channel + ": image names camera '" + image.camera + "'";
  }
  if (refusal.empty()) return true;
  status_.Rejected();
  status_.Note(refusal);
  return false;
}

void CarvingService::OnImage(image_t&& image, std::span<const uint8_t> bytes,
                             const std::string& channel, const std::string& camera_of_bus,
                             int64_t receive_utime) {
  status_.Received();
  if (!AcceptableImage(image, bytes, channel, camera_of_bus)) return;
  std::optional<ArrivedView> arrived = PrepareOnArrival(image, bytes);
  // Kept for the note on a rejection (the image moves into the assembler).
  const std::string camera = image.camera;
  const int64_t trigger_seq = image.trigger_seq;
  const int64_t dropped_before = assembler_.counters().DroppedSets();
  AssemblyResult result = assembler_.Add(std::move(image), receive_utime);
  CountAssemblyDrops(dropped_before);
  const bool accepted =
      result.outcome == AssemblyOutcome::kPending || result.outcome == AssemblyOutcome::kCompleted;
  if (accepted && arrived) prepared_.Keep(arrived->image, std::move(arrived->view));
  if (result.outcome == AssemblyOutcome::kCompleted) {
    CarvingJob job{std::move(*result.completed), {}};
    job.views = prepared_.Take(job.set);
    worker_.Push(std::move(job));
  } else if (IsRejection(result.outcome)) {
    status_.Rejected();
    status_.Note(camera + ": " + AssemblyOutcomeName(result.outcome) + " (trigger " +
                 std::to_string(trigger_seq) + ")");
  }
}

int CarvingService::RigIndex(const std::string& camera) const {
  const std::vector<Camera>& cameras = stage_.rig().cameras;
  for (size_t k = 0; k < cameras.size(); ++k) {
    if (cameras[k].name == camera) return static_cast<int>(k);
  }
  return -1;
}

std::optional<CarvingService::ArrivedView> CarvingService::PrepareOnArrival(
    const image_t& image, std::span<const uint8_t> bytes) {
  const int camera = RigIndex(image.camera);
  if (camera < 0) return std::nullopt;  // the assembler refuses it
  ArrivedView arrived{IdentityOf(static_cast<size_t>(camera), image), view_pool_.Take()};
  // On failure the view keeps the reason, for the set to report.
  stage_.PrepareView(arrived.image.camera, image, bytes, &arrived.view, &compact_scratch_);
  return arrived;
}

void CarvingService::CountAssemblyDrops(int64_t before) {
  const int64_t dropped = assembler_.counters().DroppedSets() - before;
  if (dropped > 0) {
    status_.Dropped(dropped);
    status_.Note(assembler_.last_drop());
  }
}

void CarvingService::Poll(int64_t now_utime) {
  const int64_t dropped_before = assembler_.counters().DroppedSets();
  assembler_.Expire(now_utime);
  CountAssemblyDrops(dropped_before);
  status_.SetQueueDepth(worker_.depth());
  int64_t images_rejected = 0;
  for (const LcmBus* bus : image_buses_.Opened()) images_rejected += bus->Rejected();
  status_.MaybePublish(bus_, now_utime, images_rejected);
}

service_status_t CarvingService::Status(int64_t now_utime) {
  int64_t rejected = 0;
  for (const LcmBus* bus : Buses()) rejected += bus->Rejected();
  return status_.Snapshot(now_utime, rejected);
}

void CarvingService::CarveAndPublish(CarvingJob& job) {
  const FrameSet& set = job.set;
  if (const std::string error = stage_.Carve(set, &job.views, &output_); !error.empty()) {
    status_.Error(FrameSetName(set) + ": " + error);
    return;
  }
  // The silhouettes first: the shape service then usually has them when the
  // cloud arrives, and measures at once.
  const int64_t now = NowUtime();
  const int64_t age = std::max<int64_t>(0, now - MeasuredUtime(set));
  output_.silhouettes_message.header.seq = voxels_seq_;
  output_.silhouettes_message.header.utime = now;
  output_.silhouettes_message.header.data_age_us = age;
  if (!bus_.Publish(channels::kSilhouettes, output_.silhouettes_message)) {
    status_.Error("could not publish on " + std::string(channels::kSilhouettes));
  }
  output_.message.header.seq = voxels_seq_++;
  output_.message.header.utime = now;
  output_.message.header.data_age_us = age;
  if (!bus_.Publish(channels::kVoxels, output_.message)) {
    status_.Error("could not publish on " + std::string(channels::kVoxels));
    return;
  }
  status_.Published();
  MaybePublishSilhouettes(set);
}

void CarvingService::MaybePublishSilhouettes(const FrameSet& set) {
  if (options_.silhouette_rate_hz <= 0) return;
  const int64_t now = NowUtime();
  if (now - last_silhouette_utime_ < static_cast<int64_t>(1e6 / options_.silhouette_rate_hz))
    return;
  last_silhouette_utime_ = now;
  for (size_t i = 0; i < output_.silhouettes.size(); ++i) {
    image_t message = ImageToMessage(output_.silhouettes[i].mask, image_t::PIXEL_MONO8);
    message.header.seq = silhouette_seq_;
    message.header.utime = now;
    message.camera = set.images[i].camera;
    message.trigger_seq = set.trigger_seq;
    message.trigger_utime = set.trigger_utime;
    message.host_utime = now;
    bus_.Publish(channels::Silhouette(message.camera), message);
  }
  ++silhouette_seq_;
}

CarvingServiceOptions LoadCarvingServiceOptions(const ServiceArgs& args) {
  return LoadServiceOptions<CarvingServiceOptions>(args.config,
                                                   {args.rig, args.backgrounds, args.lcm_url});
}

service_status_t RunCarvingService(const ServiceArgs& args, const std::atomic<bool>& stop,
                                   std::ostream& log) {
  const CarvingServiceOptions options = LoadCarvingServiceOptions(args);
  RigSetup setup = LoadRigSetup(options.rig, options.backgrounds);
  log << "shapesense-carving: " << setup.rig.cameras.size() << " cameras, voxel size "
      << options.carving.voxel_size << " mm; building the carving table\n";
  LcmBus bus(options.lcm_url);
  CarvingService service(options, std::move(setup), bus);
  log << "shapesense-carving: running on "
      << (options.lcm_url.empty() ? "LCM's default" : options.lcm_url) << '\n';
  // Ready only now: the table is built and the images subscribed to.
  SystemdNotifier supervisor;
  // The loop pings; the carving runs on the worker, which must not hang either.
  supervisor.SetHealthCheck(
      [&] { return !service.WorkerBusyLongerThan(supervisor.watchdog_timeout() / 2); });
  supervisor.Ready("carving frame-sets");
  RunBusLoop(
      service.Buses(), stop, args.duration_s, [&](int64_t now) { service.Poll(now); }, supervisor);
  return service.Status(NowUtime());
}

}  // namespace shapesense
