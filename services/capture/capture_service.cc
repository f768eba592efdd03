#include "services/capture/capture_service.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <latch>
#include <mutex>
#include <thread>
#include <vector>

#include "libs/core/error.h"
#include "runtime/config_file.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/image_buses.h"
#include "runtime/lcm/service_status.h"
#include "runtime/lcm/truth_message.h"
#include "runtime/process/systemd_notify.h"
#include "services/capture/image_message.h"
#include "services/capture/trigger_queue.h"

namespace shapesense {
namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kGrabTimeout = std::chrono::milliseconds(100);  // bounds the reaction to a stop
constexpr auto kStatusTick = std::chrono::milliseconds(50);
constexpr auto kFirstSetWait = std::chrono::milliseconds(2000);

// One camera, its grab thread and its trigger relay.
struct CameraSlot {
  CameraConfig config;
  std::unique_ptr<CameraBackend> backend;
  LcmBus* image_bus = nullptr;  // its own port on a udpm rig (runtime/lcm/image_buses.h)
  std::mutex open_mutex;        // Open and Close against the relay's Trigger
  std::atomic<bool> up{false};
  std::atomic<int64_t> missed_triggers{0};  // frame-sets the camera was not triggered for
  TriggerQueue relay{8};
  // Grab thread only:
  bool failing = false;
  bool gap_open = false;  // an outage whose end (the next image) is still to be reported
  int64_t down_since_utime = 0;
  int64_t last_image_utime = 0;  // host time of the last image published, 0: none yet
  int64_t last_image_seq = -1;   // its trigger sequence
  Clock::time_point last_attempt{};
  std::atomic<int64_t> published{0};  // the trigger thread waits for the first
  int64_t outages = 0;
  // Status (main) thread only: what of the backend's counters the status has counted.
  int64_t counted_drops = 0;
};

// A backend's message without its leading "NAME: ", which the service adds itself.
std::string Unnamed(const CameraSlot& slot, const std::string& what) {
  const std::string prefix = slot.config.name + ": ";
  return what.compare(0, prefix.size(), prefix) == 0 ? what.substr(prefix.size()) : what;
}

std::string Seconds(double seconds) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g s", seconds);
  return text;
}

void LogToStderr(const std::string& line) { std::fprintf(stderr, "[capture] %s\n", line.c_str()); }

// Real cameras must give the configured size; replay and simulated images have their source's.
bool HasConfiguredSize(const CameraConfig& config, const cv::Mat& image) {
  if (config.backend != "aravis" && config.backend != "v4l2") return true;
  return image.cols == config.width && image.rows == config.height;
}

class CaptureService {
 public:
  CaptureService(const CaptureServiceArgs& args, LcmBus& bus)
      : args_(args),
        options_(args.options),
        bus_(bus),
        image_buses_(bus, args.options.cameras.size()),
        compression_(ParseCompression(args.options.compression)),
        log_(args.log ? args.log : LogToStderr),
        started_(static_cast<std::ptrdiff_t>(args.options.cameras.size())),
        preview_bus_(bus.options()),
        previews_(options_.preview, options_.trigger_rate_hz,
                  [this](const std::string& channel, image_t& preview) {
                    preview_bus_.Publish(channel, preview);
                  }) {}

  CaptureSummary Run(const std::atomic<bool>& stop);

 private:
  // A mutable message, so that the bus names this host in it in place (a
  // const one it would copy first: ~1 MB for an image).
  template <class Message>
  bool Publish(const std::string& channel, Message&& message, LcmBus* bus = nullptr) {
    std::lock_guard lock(publish_mutex_);
    return (bus != nullptr ? *bus : bus_).Publish(channel, message);
  }
  void MakeSlots();
  bool TryOpen(CameraSlot& slot);
  void MarkDown(CameraSlot& slot, const std::string& why);
  void GrabLoop(CameraSlot& slot);
  void Grab(CameraSlot& slot);
  void PublishFrame(CameraSlot& slot, const CameraFrame& frame);
  void ReportGap(CameraSlot& slot, const CameraFrame& frame);
  void WaitForFirstImages();
  void TriggerLoop();
  void TriggerAll(int64_t seq, int64_t utime);
  void RelayLoop(CameraSlot& slot);
  void PublishTruth(int64_t seq, int64_t utime);
  // `last`: publish now (the final counts, as the service stops).
  void UpdateStatus(bool last = false);
  void SleepUntil(Clock::time_point until) const;
  CaptureSummary Summary() const;
  void MaybeReady(SystemdNotifier& supervisor);

  const CaptureServiceArgs& args_;
  const CaptureServiceOptions& options_;
  LcmBus& bus_;
  // Camera k of options_.cameras publishes on image bus k: list the cameras
  // in the rig's order, as the carving service listens in that order.
  ImageBuses image_buses_;
  const ImageCompression compression_;
  const std::function<void(const std::string&)> log_;
  std::mutex publish_mutex_;
  ServiceStatus status_{"capture"};
  std::shared_ptr<const SimulatedWorld> world_;
  std::vector<std::unique_ptr<CameraSlot>> slots_;
  std::latch started_;  // every camera has had its first attempt to open
  std::atomic<bool> stopping_{false};
  bool ready_ = false;  // READY=1 sent
  std::atomic<int64_t> triggers_{0};
  int64_t truth_seq_ = 0;
  int64_t stale_trigger_us_ = 0;
  // The previews' own bus: their thread runs at SCHED_IDLE, and on the
  // grab threads' bus it held the lock they publish under while the machine
  // kept it off the CPU, delaying every camera's images behind it.
  LcmBus preview_bus_;
  PreviewPublisher previews_;  // last: its thread publishes through the above
};

void CaptureService::MakeSlots() {
  const BackendContext context{world_};
  for (const CameraConfig& config : options_.cameras) {
    auto slot = std::make_unique<CameraSlot>();
    slot->config = config;
    slot->image_bus = &image_buses_.ForCamera(slots_.size());
    slot->backend = args_.make_backend ? args_.make_backend(config, context)
                                       : MakeCameraBackend(config, context);
    slots_.push_back(std::move(slot));
  }
}

bool CaptureService::TryOpen(CameraSlot& slot) {
  std::lock_guard lock(slot.open_mutex);
  slot.last_attempt = Clock::now();
  try {
    slot.backend->Open();
  } catch (const std::exception& e) {
    if (!slot.failing) MarkDown(slot, "cannot open: " + Unnamed(slot, e.what()));
    return false;
  }
  if (slot.failing) {
    const double seconds = static_cast<double>(NowUtime() - slot.down_since_utime) * 1e-6;
    log_(slot.config.name + ": reopened after " + Seconds(seconds) + " down");
  }
  slot.failing = false;
  slot.up = true;
  return true;
}

// On the slot's grab thread, holding slot.open_mutex.
void CaptureService::MarkDown(CameraSlot& slot, const std::string& why) {
  slot.up = false;
  slot.failing = true;
  ++slot.outages;
  slot.gap_open = true;
  slot.down_since_utime = NowUtime();
  const std::string line =
      slot.config.name + ": " + why + "; retrying every " + Seconds(options_.reconnect_interval_s);
  log_(line);
  status_.Error(line);
}

void CaptureService::GrabLoop(CameraSlot& slot) {
  TryOpen(slot);
  started_.count_down();
  const auto retry = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(options_.reconnect_interval_s));
  while (!stopping_) {
    if (slot.up) {
      Grab(slot);
    } else {
      SleepUntil(slot.last_attempt + retry);
      if (!stopping_) TryOpen(slot);
    }
  }
  std::lock_guard lock(slot.open_mutex);
  slot.backend->Close();
  slot.up = false;
}

void CaptureService::Grab(CameraSlot& slot) {
  CameraFrame frame;
  try {
    if (slot.backend->Grab(kGrabTimeout, &frame)) PublishFrame(slot, frame);
  } catch (const std::exception& e) {
    std::lock_guard lock(slot.open_mutex);
    slot.backend->Close();
    // Backends say "lost (why)" themselves; anything else thrown by Grab loses the camera too.
    const std::string what = Unnamed(slot, e.what());
    MarkDown(slot, what.find("lost") != std::string::npos ? what : "lost: " + what);
  }
}

void CaptureService::PublishFrame(CameraSlot& slot, const CameraFrame& frame) {
  status_.Received();
  if (!HasConfiguredSize(slot.config, frame.image)) {
    status_.Error(slot.config.name + ": dropped an image of the wrong size");
    return;
  }
  image_t message = ToImageMessage(slot.config.name, frame, slot.published, NowUtime(),
                                   compression_, options_.png_level);
  if (!Publish(channels::Image(slot.config.name), message, slot.image_bus)) {
    status_.Error(slot.config.name + ": LCM publish failed");
    return;
  }
  ++slot.published;
  status_.Published();
  previews_.Offer(slot.config.name, frame);
  if (slot.gap_open) ReportGap(slot, frame);
  slot.last_image_utime = frame.host_utime;
  slot.last_image_seq = frame.trigger_seq;
}

// The first image after an outage: how long the camera gave none, and (when
// triggered in software) which frame-sets it missed.
void CaptureService::ReportGap(CameraSlot& slot, const CameraFrame& frame) {
  slot.gap_open = false;
  std::string line = slot.config.name + ": images again";
  if (slot.last_image_utime > 0) {
    line += " after " +
            Seconds(static_cast<double>(frame.host_utime - slot.last_image_utime) * 1e-6) +
            " without";
  }
  if (frame.trigger_seq >= 0) {
    const int64_t missed = frame.trigger_seq - slot.last_image_seq - 1;
    line += ", " + std::to_string(missed) + " frame-sets missed (" +
            std::to_string(slot.last_image_seq + 1) + "-" + std::to_string(frame.trigger_seq - 1) +
            ")";
  }
  log_(line);
}

// Posts the trigger to every software-triggered camera's relay: the trigger
// thread never waits on a camera (a vanished GigE camera blocks its trigger
// for seconds).
void CaptureService::TriggerAll(int64_t seq, int64_t utime) {
  for (const auto& slot : slots_) {
    if (slot->config.Trigger() != TriggerMode::kSoftware) continue;
    if (slot->up) {
      slot->relay.Push({seq, utime});
    } else {
      ++slot->missed_triggers;
    }
  }
}

// Triggers one camera. A trigger that waited too long (the camera was busy
// or blocked) is skipped: its exposure would not belong to its frame-set.
// Triggers to one camera are at least half a period apart: a camera still
// busy with its last image would otherwise get the trigger that waited
// meanwhile right after the last, and one that keeps a single
// pending-trigger flag (as Aravis's fake camera does, served at its next
// poll) would answer both with one image.
void CaptureService::RelayLoop(CameraSlot& slot) {
  const auto spacing = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(0.5 / options_.trigger_rate_hz));
  Clock::time_point next_send{};
  while (!stopping_) {
    const std::optional<QueuedTrigger> trigger = slot.relay.Pop(kGrabTimeout);
    if (!trigger) continue;
    SleepUntil(next_send);
    // A camera being opened or closed is skipped rather than waited for.
    std::unique_lock lock(slot.open_mutex, std::try_to_lock);
    if (!lock.owns_lock() || !slot.up || NowUtime() - trigger->utime > stale_trigger_us_) {
      ++slot.missed_triggers;
      continue;
    }
    try {
      slot.backend->Trigger(trigger->seq, trigger->utime);
    } catch (const std::exception&) {
      ++slot.missed_triggers;  // the grab thread finds out whether the camera is lost
    }
    next_send = Clock::now() + spacing;
  }
}

void CaptureService::PublishTruth(int64_t seq, int64_t utime) {
  const TrajectoryPose pose = world_->PoseAtUtime(utime);
  const TubeScene scene = SceneOf(world_->options().trajectory, world_->rig(), pose);
  Publish(channels::kTruth, FrameSetTruth(scene, pose, seq, utime, truth_seq_++, NowUtime()));
}

// Waits (at most kFirstSetWait) until every software-triggered camera that is
// up has published an image. A camera's first image after its acquisition
// started can be slow (Aravis's fake camera looks for its first trigger only
// every 100 ms); triggering on meanwhile would make it answer several
// triggers with one image, and their frame-sets would be lost.
void CaptureService::WaitForFirstImages() {
  const auto end = Clock::now() + kFirstSetWait;
  const auto waiting = [&] {
    return std::any_of(slots_.begin(), slots_.end(), [](const auto& slot) {
      return slot->config.Trigger() == TriggerMode::kSoftware && slot->up && slot->published == 0;
    });
  };
  while (!stopping_ && Clock::now() < end && waiting()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

void CaptureService::TriggerLoop() {
  started_.wait();
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / options_.trigger_rate_hz));
  Clock::time_point next = Clock::now();
  for (int64_t seq = 0; !stopping_; ++seq) {
    SleepUntil(next);
    if (stopping_) break;
    const int64_t utime = NowUtime();
    TriggerAll(seq, utime);
    if (world_ && options_.publish_truth) PublishTruth(seq, utime);
    triggers_ = seq + 1;
    if (seq == 0) WaitForFirstImages();
    // After a stall the clock restarts from now rather than firing a burst.
    next = std::max(next + period, Clock::now());
  }
}

void CaptureService::SleepUntil(Clock::time_point until) const {
  while (!stopping_ && Clock::now() < until) {
    std::this_thread::sleep_for(std::min<Clock::duration>(kStatusTick, until - Clock::now()));
  }
}

// What a camera's dropped frame-sets were (the last status's last_error).
std::string DropBreakdown(const CameraSlot& slot, const CameraStats& stats) {
  return slot.config.name + ": " + std::to_string(stats.incomplete) + " incomplete images, " +
         std::to_string(stats.missed_triggers) + " triggers answered with no image, " +
         std::to_string(slot.missed_triggers + slot.relay.Dropped()) +
         " triggers not sent (camera down, busy or too late)" +
         (stats.unmatched_reasons.empty() ? "" : " (" + stats.unmatched_reasons + ")");
}

void CaptureService::UpdateStatus(bool last) {
  std::string breakdown;
  for (const auto& slot : slots_) {
    const CameraStats stats = slot->backend->Stats();
    const int64_t drops =
        stats.incomplete + stats.missed_triggers + slot->missed_triggers + slot->relay.Dropped();
    status_.Dropped(drops - slot->counted_drops);
    slot->counted_drops = drops;
    if (drops > 0) breakdown += (breakdown.empty() ? "" : "; ") + DropBreakdown(*slot, stats);
  }
  std::lock_guard lock(publish_mutex_);
  if (!last) {
    status_.MaybePublish(bus_, NowUtime());
    return;
  }
  // The last status says why frame-sets were dropped (while running, the
  // last error, e.g. a camera lost, says more).
  if (!breakdown.empty()) status_.Note("frame-sets dropped: " + breakdown);
  status_.Publish(bus_, NowUtime());
}

CaptureSummary CaptureService::Summary() const {
  CaptureSummary summary;
  summary.triggers = triggers_;
  for (const auto& slot : slots_) {
    summary.cameras[slot->config.name] = {slot->published.load(), slot->outages,
                                          slot->missed_triggers + slot->relay.Dropped(),
                                          slot->backend->Stats()};
  }
  return summary;
}

// Ready once every camera has had its first attempt to open: those that
// failed are retried, and the status says how many are up.
void CaptureService::MaybeReady(SystemdNotifier& supervisor) {
  if (ready_ || !started_.try_wait()) return;
  ready_ = true;
  const auto up =
      std::count_if(slots_.begin(), slots_.end(), [](const auto& s) { return s->up.load(); });
  supervisor.Ready(std::to_string(up) + " of " + std::to_string(slots_.size()) + " cameras up");
}

CaptureSummary CaptureService::Run(const std::atomic<bool>& stop) {
  world_ = MakeSimulatedWorld(options_, NowUtime());
  MakeSlots();
  // A trigger that would leave a fifth of a period (at least 2 ms, at most
  // half a period) after its frame-set's time is stale: the camera's image
  // would show the scene that much later than its set's time says.
  const double period_us = 1e6 / options_.trigger_rate_hz;
  stale_trigger_us_ =
      static_cast<int64_t>(std::min(0.5 * period_us, std::max(2'000.0, 0.2 * period_us)));
  std::vector<std::thread> threads;
  bool any_software = false;
  for (const auto& slot : slots_) {
    threads.emplace_back([this, s = slot.get()] { GrabLoop(*s); });
    if (slot->config.Trigger() != TriggerMode::kSoftware) continue;
    any_software = true;
    threads.emplace_back([this, s = slot.get()] { RelayLoop(*s); });
  }
  if (any_software) threads.emplace_back([this] { TriggerLoop(); });
  SystemdNotifier supervisor;
  const Clock::time_point end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                   std::chrono::duration<double>(args_.duration_s));
  while (!stop && (args_.duration_s <= 0.0 || Clock::now() < end)) {
    MaybeReady(supervisor);
    supervisor.Watchdog();
    std::this_thread::sleep_for(kStatusTick);
    UpdateStatus();
  }
  supervisor.Stopping();
  stopping_ = true;
  for (std::thread& thread : threads) thread.join();
  UpdateStatus(/*last=*/true);
  return Summary();
}

}  // namespace

std::shared_ptr<const SimulatedWorld> MakeSimulatedWorld(const CaptureServiceOptions& options,
                                                         int64_t origin_utime) {
  const bool any_simulated =
      std::any_of(options.cameras.begin(), options.cameras.end(),
                  [](const CameraConfig& c) { return c.backend == "simulated"; });
  if (!any_simulated) return nullptr;
  SimulationOptions simulation = options.simulation;
  if (!simulation.trajectory_file.empty()) {
    simulation.trajectory = LoadOptionsFile<TrajectoryOptions>(simulation.trajectory_file);
  }
  return std::make_shared<SimulatedWorld>(LoadSimulationRig(options.rig), simulation, origin_utime);
}

CaptureSummary RunCaptureService(const CaptureServiceArgs& args, const std::atomic<bool>& stop,
                                 LcmBus& bus) {
  if (const std::string error = args.options.Validate(); !error.empty()) throw InputError(error);
  CaptureService service(args, bus);
  return service.Run(stop);
}

CaptureSummary RunCaptureService(const CaptureServiceArgs& args, const std::atomic<bool>& stop) {
  LcmBus bus(args.lcm_url);
  return RunCaptureService(args, stop, bus);
}

}  // namespace shapesense
