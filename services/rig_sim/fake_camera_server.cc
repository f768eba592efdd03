#include "services/rig_sim/fake_camera_server.h"

#include <arv.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <future>
#include <stdexcept>

#include "services/capture/genicam_pixel_formats.h"
#include "services/rig_sim/raw_image.h"

namespace shapesense {
namespace {

constexpr size_t kKeptFrameSets = 1000;
constexpr size_t kSerialLimit = 15;  // GigE Vision serial numbers hold 16 bytes with the NUL
// The fake camera looks for a software trigger at this rate once streaming:
// the delay between a trigger and its image is up to one period. Its thread
// waits on its sockets with timeouts rounded down to milliseconds, so it
// spins through the last millisecond of every period: at 1 kHz it spun all
// the time, about a third of the rig-sim's CPU at 30 Hz.
constexpr double kTriggerPollHz = 250.0;
// Render threads: all cores but one. A camera's own thread answers its
// client (GigE Vision control) and sends its images; it hands the rendering
// to these threads, which run at a lower priority. Rendering in the camera's
// thread, with every core busy rendering, kept a camera's thread from its
// next poll long enough for the next trigger to arrive, and it answered both
// with one image.
int RenderThreads() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()) - 1);
}
constexpr int kRenderNiceness = 10;

// How often the watcher looks for triggers.
constexpr auto kWatchPeriod = std::chrono::milliseconds(1);

int64_t HostUtime() { return g_get_real_time(); }

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
  // image): the time the trigger reached the camera, which its image may
  // follow by up to a trigger poll (or, for a session's first image, by up
  // to the fake camera's 100 ms first poll).
  std::atomic<int64_t> trigger_seen_utime{-1};
};

namespace {

void FillPattern(ArvBuffer* buffer, void* slot_data, guint32 /*exposure_us*/, guint32 /*gain*/,
                 ArvPixelFormat pixel_format) {
  // The buffer belongs to the fake camera; the fill callback is where it is written.
  void* data = const_cast<void*>(arv_buffer_get_data(buffer, nullptr));
  const auto* slot = static_cast<const FakeCameraServer::Slot*>(slot_data);
  const int64_t waited_us =
      slot->server->Fill(slot->camera, data, arv_buffer_get_image_width(buffer),
                         arv_buffer_get_image_height(buffer), pixel_format);
  // The image's timestamp is its exposure, when the trigger arrived, as a real
  // camera's: the client tells which trigger an image answers by it.
  const auto stamped = static_cast<int64_t>(arv_buffer_get_timestamp(buffer));
  if (waited_us > 0 && stamped > waited_us * 1000) {
    arv_buffer_set_timestamp(buffer, static_cast<guint64>(stamped - waited_us * 1000));
  }
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
      clock_(static_cast<int>(rig_.cameras.size())) {
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
  slot.trigger_seen_utime = -1;
}

}  // namespace

// Notes when a software trigger reaches each camera: its thread serves the
// trigger at its next poll, or after the image it is busy with.
void FakeCameraServer::WatchTriggers() {
  while (!stop_watching_) {
    {
      std::lock_guard lock(slots_mutex_);
      for (const auto& slot : slots_) {
        ArvFakeCamera* fake = slot->gv_camera != nullptr
                                  ? arv_gv_fake_camera_get_fake_camera(slot->gv_camera)
                                  : nullptr;
        const bool acquiring = fake != nullptr && arv_fake_camera_get_acquisition_status(fake) != 0;
        if (fake != nullptr && !acquiring) slot->trigger_before_start = TriggerWaiting(fake);
        if (acquiring && !slot->acquiring && slot->trigger_before_start) {
          ForgetEarlierTriggers(*slot, fake);
        }
        slot->acquiring = acquiring;
        int64_t none = -1;
        if (acquiring && TriggerWaiting(fake)) {
          slot->trigger_seen_utime.compare_exchange_strong(none, HostUtime());
        }
      }
    }
    std::this_thread::sleep_for(kWatchPeriod);
  }
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
}

void FakeCameraServer::Stop(int camera) {
  Slot& slot = *slots_.at(static_cast<size_t>(camera));
  std::lock_guard lock(slots_mutex_);
  if (slot.gv_camera == nullptr) return;
  g_object_unref(slot.gv_camera);  // joins the camera's thread
  slot.gv_camera = nullptr;
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

FrameSet FakeCameraServer::Assign(int camera, int64_t trigger_utime) {
  std::lock_guard lock(mutex_);
  const FrameSetClock::Slot slot = clock_.AssignByTrigger(camera, trigger_utime);
  // A set joined is one of the clock's recent ones, all still in the history.
  for (auto set = history_.rbegin(); !slot.opened && set != history_.rend(); ++set) {
    if (set->seq == slot.seq) return *set;
  }
  FrameSet set;
  set.seq = slot.seq;
  set.trigger_utime = slot.first_utime;
  set.t_seconds = static_cast<double>(slot.first_utime - origin_utime_) * 1e-6;
  if (plant_ != nullptr) {
    set.scene = std::make_shared<const TubeScene>(plant_->SceneAtUtime(slot.first_utime));
  } else {
    set.pose = PoseAt(trajectory_, set.t_seconds);
    set.scene = std::make_shared<const TubeScene>(SceneOf(trajectory_, rig_, set.pose));
  }
  new_sets_.push_back(set);
  history_.push_back(set);
  if (new_sets_.size() > kKeptFrameSets) new_sets_.pop_front();
  if (history_.size() > kKeptFrameSets) history_.pop_front();
  return set;
}

std::vector<FrameSet> FakeCameraServer::TakeNewFrameSets() {
  std::lock_guard lock(mutex_);
  std::vector<FrameSet> taken(new_sets_.begin(), new_sets_.end());
  new_sets_.clear();
  return taken;
}

std::optional<FrameSet> FakeCameraServer::Find(int64_t seq) const {
  std::lock_guard lock(mutex_);
  for (const FrameSet& set : history_) {
    if (set.seq == seq) return set;
  }
  return std::nullopt;
}

cv::Mat FakeCameraServer::Render(int camera, const FrameSet& set) const {
  const uint64_t noise =
      Mix(Mix(seed_) ^ static_cast<uint64_t>(set.seq)) ^ static_cast<uint64_t>(camera);
  const Slot& slot = *slots_.at(static_cast<size_t>(camera));
  const RenderedView view =
      slot.renderer->Render(*set.scene, trajectory_.render, static_cast<uint32_t>(Mix(noise)))[0];
  return backdrop_only_ ? view.background : view.image;
}

cv::Mat FakeCameraServer::RenderOnWorker(int camera, const FrameSet& set) {
  std::packaged_task<cv::Mat()> job([this, camera, set] { return Render(camera, set); });
  std::future<cv::Mat> image = job.get_future();
  {
    std::lock_guard lock(render_mutex_);
    render_jobs_.push_back(std::move(job));
  }
  render_ready_.notify_one();
  return image.get();
}

void FakeCameraServer::RenderJobs() {
  const int niceness = nice(kRenderNiceness);  // this thread only (Linux); best effort
  (void)niceness;
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

// Never throws: it runs inside Aravis's C thread. An image it cannot make is
// sent black and counted.
int64_t FakeCameraServer::Fill(int camera, void* data, int width, int height,
                               uint32_t pixel_format) {
  const size_t size = static_cast<size_t>(width) * height * RawBytesPerPixel(pixel_format);
  Slot& slot = *slots_[static_cast<size_t>(camera)];
  const int64_t now = HostUtime();
  // The image answers the trigger the watcher saw (else one that came
  // within a poll, unseen).
  const int64_t seen = slot.trigger_seen_utime.exchange(-1);
  const int64_t asked = seen > 0 && seen <= now ? seen : now;
  try {
    const cv::Mat view = RenderOnWorker(camera, Assign(camera, asked));
    if (EncodeRawImage(view, pixel_format, width, height, static_cast<uint8_t*>(data), size)) {
      ++images_served_;
      return now - asked;
    }
  } catch (...) {
  }
  ++errors_;
  if (size > 0) std::memset(data, 0, size);
  return now - asked;
}

}  // namespace shapesense
