#include "services/rig_sim/fake_camera_server.h"

#include <arpa/inet.h>
#include <arv.h>
#include <netinet/in.h>
#include <pthread.h>
#include <sched.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <future>
#include <stdexcept>
#include <thread>

#include "libs/camera/genicam_pixel_formats.h"
#include "runtime/host_clock.h"
#include "services/rig_sim/raw_image.h"

namespace shapesense {
namespace {

constexpr size_t kKeptExposures = 1000;
// GigE Vision 1.x block ids are 16-bit and skip 0.
constexpr int64_t kLastBlockId = 0xffff;
constexpr size_t kSerialLimit = 15;  // GigE Vision serial numbers hold 16 bytes with the NUL
// The fake camera looks for a software trigger at this rate once streaming:
// the delay between a trigger and its image is up to one period. Its thread
// waits on its sockets with timeouts rounded down to milliseconds, so it
// spins through the last millisecond of every period: at 1 kHz it spun all
// the time, about a third of the rig-sim's CPU at 30 Hz.
constexpr double kTriggerPollHz = 250.0;
// Render threads: all cores but one. A camera's own thread answers its
// client (GigE Vision control) and sends its images; it hands the rendering
// to these threads. Rendering in the camera's thread, with every core busy
// rendering, kept a camera's thread from its next poll long enough for the
// next trigger to arrive, and it answered both with one image. They run at
// the normal priority: niced, they starved on a loaded machine while the
// camera's thread waited for them and could not take its next trigger.
int RenderThreads() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()) - 1);
}

// How often the watcher looks for triggers: the exposure of a camera starts
// up to this late after its trigger arrived, so the cameras of one trigger
// expose this much apart at most, beyond their triggers' own spread.
constexpr auto kWatchPeriod = std::chrono::microseconds(250);

// Aravis's fake camera (0.8.26) can fall asleep for up to 100 ms with a
// trigger waiting: its loop computes the poll timeout as an unsigned
// difference, and when its period ends between the loop's test and that
// subtraction, the difference wraps into a long poll that only a packet
// ends. The next trigger's packet then ends it and both triggers get one
// image (about 1% of triggers, more on a loaded machine). A trigger still
// unserved this long after the watcher saw it (the camera's poll period
// and a margin) rings the camera's doorbell: a GVCP register read, whose
// arrival ends the poll, so that the camera serves its trigger.
constexpr int64_t kDoorbellAfterUs = 1'000'000 / static_cast<int64_t>(kTriggerPollHz) + 1'000;
constexpr uint16_t kGvcpPort = 3956;

// The watcher stands for the cameras' trigger inputs, which hardware serves
// within microseconds whatever the host does: it runs at this real-time
// priority where the process may (as root), above the services' and any
// other load's, so that a busy machine delays the sensing, never the
// exposures. At normal priority a starved watcher stamped exposures past
// their triggers' windows and the capture service rightly refused them.
constexpr int kWatcherRealtimePriority = 20;

// Raises `thread` to kWatcherRealtimePriority (SCHED_FIFO), or says on
// standard error why it stays at normal priority.
void RaiseToRealtime(std::thread& thread) {
  sched_param param{};
  param.sched_priority = kWatcherRealtimePriority;
  const int error = pthread_setschedparam(thread.native_handle(), SCHED_FIFO, &param);
  if (error != 0) {
    std::fprintf(stderr,
                 "rig-sim: the trigger watcher runs at normal priority (real-time refused: "
                 "%s); under load exposures may be stamped late and their images refused\n",
                 std::strerror(error));
  }
}

uint64_t Mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Called by a fake camera's thread for every image, in the client's format.
void FillPattern(ArvBuffer* buffer, void* slot_data, guint32 /*exposure_us*/, guint32 /*gain*/,
                 ArvPixelFormat pixel_format);

}  // namespace

struct FakeCameraServer::Slot {
  FakeCameraServer* server = nullptr;
  int camera = 0;
  std::string address;
  std::string serial;
  std::unique_ptr<SceneRenderer> renderer;  // this camera alone
  ArvGvFakeCamera* gv_camera = nullptr;     // null while stopped
  bool acquiring = false;                   // the watcher's last look
  bool trigger_before_start = false;        // a trigger written while not acquiring
  // When the watcher saw a software trigger waiting (-1: none since the last
  // image): the exposure's start. The fake camera's thread serves it at its
  // next poll, or after the image it is busy with. `seen_fills` is `fills`
  // when the watcher looked: a sighting the camera's thread overtook (it
  // served the trigger between the watcher's look and its note) belongs to
  // no later image.
  std::mutex seen_mutex;
  int64_t trigger_seen_utime = -1;
  int64_t seen_fills = 0;
  int64_t fills = 0;
  bool doorbell_rung = false;  // for the waiting trigger (watcher only)
  int doorbell = -1;           // UDP socket to the camera's GVCP port (-1: none)
  int64_t exposures = 0;       // frames made; the block id is its 16-bit form
  // The last image sent, for the repeat fault (the camera's thread only).
  std::vector<uint8_t> last_image;
  int64_t last_frame_id = 0;
  int64_t last_exposure_utime = 0;
};

namespace {

void FillPattern(ArvBuffer* buffer, void* slot_data, guint32 /*exposure_us*/, guint32 /*gain*/,
                 ArvPixelFormat pixel_format) {
  // The buffer belongs to the fake camera; the fill callback is where it is written.
  void* data = const_cast<void*>(arv_buffer_get_data(buffer, nullptr));
  const auto* slot = static_cast<const FakeCameraServer::Slot*>(slot_data);
  const FakeCameraServer::Stamp stamp =
      slot->server->Fill(slot->camera, data, arv_buffer_get_image_width(buffer),
                         arv_buffer_get_image_height(buffer), pixel_format);
  // What a PTP-synchronised camera reports: its exposure on the rig's clock
  // and its own count of exposures.
  arv_buffer_set_timestamp(buffer, static_cast<guint64>(stamp.exposure_utime) * 1000);
  arv_buffer_set_frame_id(buffer, static_cast<guint64>(stamp.frame_id));
}

std::string SerialOf(const Camera& camera, int index) {
  if (!camera.name.empty() && camera.name.size() <= kSerialLimit) return camera.name;
  return "SIM" + std::to_string(index);
}

}  // namespace

FakeCameraServer::FakeCameraServer(Rig rig, TrajectoryOptions trajectory,
                                   std::vector<std::string> addresses, uint32_t seed,
                                   int64_t origin_utime)
    : rig_(std::move(rig)),
      trajectory_(std::move(trajectory)),
      seed_(seed),
      origin_utime_(origin_utime),
      history_(rig_.cameras.size()) {
  if (addresses.size() != rig_.cameras.size()) {
    throw std::invalid_argument("rig-sim: " + std::to_string(rig_.cameras.size()) +
                                " cameras need as many addresses, got " +
                                std::to_string(addresses.size()));
  }
  for (size_t i = 0; i < rig_.cameras.size(); ++i) {
    auto slot = std::make_unique<Slot>();
    slot->server = this;
    slot->camera = static_cast<int>(i);
    slot->address = addresses[i];
    slot->serial = SerialOf(rig_.cameras[i], static_cast<int>(i));
    Rig one = rig_;
    one.cameras = {rig_.cameras[i]};
    slot->renderer = std::make_unique<SceneRenderer>(one);
    slots_.push_back(std::move(slot));
  }
  watcher_ = std::thread([this] { WatchTriggers(); });
  RaiseToRealtime(watcher_);
  for (int i = 0; i < RenderThreads(); ++i) {
    render_threads_.emplace_back([this] { RenderJobs(); });
  }
}

FakeCameraServer::~FakeCameraServer() {
  stop_watching_ = true;
  watcher_.join();
  for (int i = 0; i < num_cameras(); ++i) Stop(i);  // their images rendered first
  {
    std::lock_guard lock(render_mutex_);
    stop_rendering_ = true;
  }
  render_ready_.notify_all();
  for (std::thread& thread : render_threads_) thread.join();
}

namespace {

// Whether a software trigger waits for the camera's thread to serve it.
bool TriggerWaiting(ArvFakeCamera* fake) {
  guint32 value = 0;
  arv_fake_camera_read_register(fake, ARV_FAKE_CAMERA_REGISTER_TRIGGER_SOFTWARE, &value);
  return value != 0;
}

// A trigger written before the acquisition started answers nothing: a
// client that has not yet noticed the camera went away and came back may
// still trigger it (a camera without a controller takes anyone's writes),
// and its image would reach the reconnected client as the answer to the
// first trigger of its own.
void ForgetEarlierTriggers(FakeCameraServer::Slot& slot, ArvFakeCamera* fake) {
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_TRIGGER_SOFTWARE, 0);
  std::lock_guard lock(slot.seen_mutex);
  slot.trigger_seen_utime = -1;
}

// A UDP socket connected to the camera's GVCP port, for its doorbell; -1
// when there can be none (an address that is not numeric).
int OpenDoorbell(const std::string& address) {
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  sockaddr_in camera{};
  camera.sin_family = AF_INET;
  camera.sin_port = htons(kGvcpPort);
  if (inet_pton(AF_INET, address.c_str(), &camera.sin_addr) != 1 ||
      connect(fd, reinterpret_cast<const sockaddr*>(&camera), sizeof(camera)) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

// Sends a GVCP READREG command for register 0 (the GigE Vision version,
// which no one writes): key 0x42, no acknowledge asked, command 0x0080,
// 4 bytes of address, request id 1, all big-endian. The camera answers
// anyway; its earlier answers are read away first.
void RingDoorbell(int fd) {
  constexpr std::array<uint8_t, 12> kReadVersion = {0x42, 0x00, 0x00, 0x80, 0x00, 0x04,
                                                    0x00, 0x01, 0x00, 0x00, 0x00, 0x00};
  std::array<uint8_t, 64> answer{};
  while (recv(fd, answer.data(), answer.size(), 0) > 0) {
  }
  // A failed send (the camera just stopped) leaves the trigger to its poll.
  [[maybe_unused]] const ssize_t sent = send(fd, kReadVersion.data(), kReadVersion.size(), 0);
}

}  // namespace

// Notes when a software trigger reaches each camera: its exposure.
void FakeCameraServer::WatchTriggers() {
  while (!stop_watching_) {
    {
      std::lock_guard lock(slots_mutex_);
      for (const auto& slot : slots_) WatchTrigger(*slot);
    }
    std::this_thread::sleep_for(kWatchPeriod);
  }
}

void FakeCameraServer::WatchTrigger(Slot& slot) {
  ArvFakeCamera* fake =
      slot.gv_camera != nullptr ? arv_gv_fake_camera_get_fake_camera(slot.gv_camera) : nullptr;
  bool acquiring = fake != nullptr && arv_fake_camera_get_acquisition_status(fake) != 0;
  if (fake != nullptr && !acquiring) {
    // The trigger register, then the status again: a trigger waiting while
    // the camera still did not acquire was written before the start. With
    // one read of the status before the trigger's, a start and its first
    // trigger that both landed in between (this thread preempted on a busy
    // machine) made that trigger look older than the start: forgotten.
    const bool waiting = TriggerWaiting(fake);
    acquiring = arv_fake_camera_get_acquisition_status(fake) != 0;
    if (!acquiring) slot.trigger_before_start = waiting;
  }
  if (acquiring && !slot.acquiring && slot.trigger_before_start) {
    ForgetEarlierTriggers(slot, fake);
  }
  slot.acquiring = acquiring;
  if (!acquiring) return;
  int64_t fills = 0;
  {
    std::lock_guard lock(slot.seen_mutex);
    if (slot.trigger_seen_utime >= 0) {  // the camera has yet to serve the last one
      if (!slot.doorbell_rung && slot.doorbell >= 0 &&
          HostUtime() - slot.trigger_seen_utime > kDoorbellAfterUs) {
        RingDoorbell(slot.doorbell);
        slot.doorbell_rung = true;
      }
      return;
    }
    fills = slot.fills;
  }
  if (!TriggerWaiting(fake)) return;
  const int64_t seen_utime = HostUtime();  // before any lock: the exposure starts now
  bool missed = false;
  {
    std::lock_guard lock(mutex_);
    missed =
        faults_.miss_ratio > 0.0 && std::bernoulli_distribution(faults_.miss_ratio)(fault_random_);
  }
  if (missed) {
    ForgetEarlierTriggers(slot, fake);
    return;
  }
  std::lock_guard lock(slot.seen_mutex);
  if (slot.fills != fills || slot.trigger_seen_utime >= 0) return;
  slot.trigger_seen_utime = seen_utime;
  slot.seen_fills = fills;
  slot.doorbell_rung = false;
}

// The fake camera starts with the rig camera's size and RGB8, and answers a
// software trigger within a millisecond (its default polls at 25 Hz).
void FakeCameraServer::Start(int camera) {
  Slot& slot = *slots_.at(static_cast<size_t>(camera));
  if (slot.gv_camera != nullptr) return;
  ArvGvFakeCamera* gv = arv_gv_fake_camera_new(slot.address.c_str(), slot.serial.c_str());
  if (!arv_gv_fake_camera_is_running(gv)) {
    g_object_unref(gv);
    throw std::runtime_error("rig-sim: camera " + rig_.cameras[static_cast<size_t>(camera)].name +
                             ": cannot serve on " + slot.address +
                             " (no interface has this address; inside a network namespace: "
                             "ip addr add " +
                             slot.address + "/8 dev lo)");
  }
  ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(gv);
  const Camera& model = rig_.cameras[static_cast<size_t>(camera)];
  const auto width = static_cast<guint32>(model.width);
  const auto height = static_cast<guint32>(model.height);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_SENSOR_WIDTH, width);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_SENSOR_HEIGHT, height);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH, width);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT, height);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT, genicam::kRgb8);
  arv_fake_camera_set_trigger_frequency(fake, kTriggerPollHz);
  arv_fake_camera_set_fill_pattern(fake, &FillPattern, &slot);
  g_object_set(gv, "gvsp-lost-ratio", packet_loss_.load(), nullptr);
  std::lock_guard lock(slots_mutex_);
  slot.gv_camera = gv;
  slot.doorbell = OpenDoorbell(slot.address);
}

void FakeCameraServer::Stop(int camera) {
  Slot& slot = *slots_.at(static_cast<size_t>(camera));
  std::lock_guard lock(slots_mutex_);
  if (slot.gv_camera == nullptr) return;
  g_object_unref(slot.gv_camera);  // joins the camera's thread
  slot.gv_camera = nullptr;
  if (slot.doorbell >= 0) close(slot.doorbell);
  slot.doorbell = -1;
}

bool FakeCameraServer::Running(int camera) const {
  std::lock_guard lock(slots_mutex_);
  return slots_.at(static_cast<size_t>(camera))->gv_camera != nullptr;
}

const std::string& FakeCameraServer::serial(int camera) const {
  return slots_.at(static_cast<size_t>(camera))->serial;
}

void FakeCameraServer::SetPacketLoss(double ratio) {
  packet_loss_ = ratio;
  std::lock_guard lock(slots_mutex_);
  for (const auto& slot : slots_) {
    if (slot->gv_camera != nullptr)
      g_object_set(slot->gv_camera, "gvsp-lost-ratio", ratio, nullptr);
  }
}

void FakeCameraServer::SetFaults(const CameraFaults& faults) {
  std::lock_guard lock(mutex_);
  faults_ = faults;
  fault_random_.seed(faults.seed);
}

CameraExposure FakeCameraServer::Expose(int camera, int64_t utime) {
  Slot& slot = *slots_[static_cast<size_t>(camera)];
  std::lock_guard lock(mutex_);
  CameraExposure exposure;
  exposure.camera = camera;
  exposure.frame_id = slot.exposures++ % kLastBlockId + 1;
  exposure.utime = utime;
  exposure.t_seconds = static_cast<double>(utime - origin_utime_) * 1e-6;
  if (plant_ != nullptr) {
    exposure.scene = std::make_shared<const TubeScene>(plant_->SceneAtUtime(utime));
  } else {
    exposure.pose = PoseAt(trajectory_, exposure.t_seconds);
    exposure.scene = std::make_shared<const TubeScene>(SceneOf(trajectory_, rig_, exposure.pose));
  }
  std::deque<CameraExposure>& history = history_[static_cast<size_t>(camera)];
  history.push_back(exposure);
  if (history.size() > kKeptExposures) history.pop_front();
  if (camera == 0) {
    new_reference_.push_back(exposure);
    if (new_reference_.size() > kKeptExposures) new_reference_.pop_front();
  }
  return exposure;
}

std::vector<CameraExposure> FakeCameraServer::TakeReferenceExposures() {
  std::lock_guard lock(mutex_);
  std::vector<CameraExposure> taken(new_reference_.begin(), new_reference_.end());
  new_reference_.clear();
  return taken;
}

std::optional<CameraExposure> FakeCameraServer::FindExposure(int camera, int64_t frame_id) const {
  std::lock_guard lock(mutex_);
  for (const CameraExposure& exposure : history_.at(static_cast<size_t>(camera))) {
    if (exposure.frame_id == frame_id) return exposure;
  }
  return std::nullopt;
}

cv::Mat FakeCameraServer::Render(const CameraExposure& exposure) const {
  const uint64_t noise = Mix(Mix(seed_) ^ static_cast<uint64_t>(exposure.utime)) ^
                         static_cast<uint64_t>(exposure.camera);
  const Slot& slot = *slots_.at(static_cast<size_t>(exposure.camera));
  const auto seed = static_cast<uint32_t>(Mix(noise));
  if (backdrop_only_)
    return slot.renderer->Render(*exposure.scene, trajectory_.render, seed)[0].background;
  // About a third of the exact renderer's cost (tests/bench/render_bench).
  return slot.renderer->RenderImage(0, *exposure.scene, trajectory_.render, seed);
}

cv::Mat FakeCameraServer::RenderOnWorker(const CameraExposure& exposure) {
  std::packaged_task<cv::Mat()> job([this, exposure] { return Render(exposure); });
  std::future<cv::Mat> image = job.get_future();
  {
    std::lock_guard lock(render_mutex_);
    render_jobs_.push_back(std::move(job));
  }
  render_ready_.notify_one();
  return image.get();
}

void FakeCameraServer::RenderJobs() {
  for (;;) {
    std::unique_lock lock(render_mutex_);
    render_ready_.wait(lock, [this] { return stop_rendering_ || !render_jobs_.empty(); });
    if (render_jobs_.empty()) return;
    std::packaged_task<cv::Mat()> job = std::move(render_jobs_.front());
    render_jobs_.pop_front();
    lock.unlock();
    job();
  }
}

// A late answer: the camera's thread holds its image back, as a camera
// whose link or host is slow; the triggers that come meanwhile wait, and
// all but the last are missed.
void FakeCameraServer::DelayAnswer() {
  double delay_ms = 0.0;
  {
    std::lock_guard lock(mutex_);
    if (faults_.answer_delay_max_ms <= 0.0) return;
    delay_ms =
        std::uniform_real_distribution<double>(0.0, faults_.answer_delay_max_ms)(fault_random_);
  }
  std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(delay_ms));
}

// The repeat fault: whether this trigger gets the camera's previous image
// again (there is one of this size).
bool FakeCameraServer::RepeatsLastImage(const Slot& slot, size_t size) {
  if (slot.last_frame_id == 0 || slot.last_image.size() != size) return false;
  std::lock_guard lock(mutex_);
  return faults_.repeat_ratio > 0.0 &&
         std::bernoulli_distribution(faults_.repeat_ratio)(fault_random_);
}

void FakeCameraServer::KeepForRepeats(Slot& slot, const void* data, size_t size,
                                      const Stamp& stamp) {
  {
    std::lock_guard lock(mutex_);
    if (faults_.repeat_ratio <= 0.0) return;
  }
  const auto* bytes = static_cast<const uint8_t*>(data);
  slot.last_image.assign(bytes, bytes + size);
  slot.last_frame_id = stamp.frame_id;
  slot.last_exposure_utime = stamp.exposure_utime;
}

// Never throws: it runs inside Aravis's C thread. An image it cannot make is
// sent black and counted.
FakeCameraServer::Stamp FakeCameraServer::Fill(int camera, void* data, int width, int height,
                                               uint32_t pixel_format) {
  const size_t size = static_cast<size_t>(width) * height * RawBytesPerPixel(pixel_format);
  Slot& slot = *slots_[static_cast<size_t>(camera)];
  const int64_t now = HostUtime();
  // The exposure began when the watcher saw the trigger (else just now: it
  // came since the watcher's last look, at most kWatchPeriod ago).
  int64_t seen = -1;
  {
    std::lock_guard lock(slot.seen_mutex);
    if (slot.seen_fills == slot.fills) seen = slot.trigger_seen_utime;
    slot.trigger_seen_utime = -1;
    ++slot.fills;
  }
  const int64_t exposure_utime = seen > 0 && seen <= now ? seen : now;
  if (RepeatsLastImage(slot, size)) {
    std::memcpy(data, slot.last_image.data(), size);
    return {slot.last_frame_id, slot.last_exposure_utime};
  }
  Stamp stamp{0, exposure_utime};
  try {
    const CameraExposure exposure = Expose(camera, exposure_utime);
    stamp.frame_id = exposure.frame_id;
    const cv::Mat view = RenderOnWorker(exposure);
    if (EncodeRawImage(view, pixel_format, width, height, static_cast<uint8_t*>(data), size)) {
      ++images_served_;
      KeepForRepeats(slot, data, size, stamp);
      DelayAnswer();
      return stamp;
    }
  } catch (...) {
  }
  ++errors_;
  if (size > 0) std::memset(data, 0, size);
  return stamp;
}

}  // namespace shapesense
