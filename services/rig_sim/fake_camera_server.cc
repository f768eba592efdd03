#include "services/rig_sim/fake_camera_server.h"

#include <arv.h>

#include <cstring>
#include <stdexcept>

#include "services/rig_sim/raw_image.h"

namespace shapesense {
namespace {

constexpr size_t kKeptFrameSets = 1000;
constexpr size_t kSerialLimit = 15;  // GigE Vision serial numbers hold 16 bytes with the NUL
// The fake camera looks for a software trigger at this rate once streaming:
// the delay between a trigger and its image.
constexpr double kTriggerPollHz = 1000.0;
constexpr uint32_t kRgb8 = 0x02180014u;
// How often the watcher looks for acquisition starts.
constexpr auto kWatchPeriod = std::chrono::milliseconds(1);
// Without a seen start, a session's first image joins sets this recent.
constexpr int64_t kFirstImageDelayUs = 150'000;

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
  std::atomic<int64_t> session_start_utime{-1};
};

namespace {

// The fake camera makes a new buffer object each time its stream starts: a
// buffer without our mark is the first image of an acquisition session.
bool MarkFirstUse(ArvBuffer* buffer) {
  static const GQuark kSeen = g_quark_from_static_string("shapesense-rig-sim-seen");
  if (g_object_get_qdata(G_OBJECT(buffer), kSeen) != nullptr) return false;
  g_object_set_qdata(G_OBJECT(buffer), kSeen, buffer);
  return true;
}

void FillPattern(ArvBuffer* buffer, void* slot_data, guint32 /*exposure_us*/, guint32 /*gain*/,
                 ArvPixelFormat pixel_format) {
  // The buffer belongs to the fake camera; the fill callback is where it is written.
  void* data = const_cast<void*>(arv_buffer_get_data(buffer, nullptr));
  const auto* slot = static_cast<const FakeCameraServer::Slot*>(slot_data);
  slot->server->Fill(slot->camera, data, arv_buffer_get_image_width(buffer),
                     arv_buffer_get_image_height(buffer), pixel_format, MarkFirstUse(buffer));
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
  watcher_ = std::thread([this] { WatchAcquisitions(); });
}

FakeCameraServer::~FakeCameraServer() {
  stop_watching_ = true;
  watcher_.join();
  for (int i = 0; i < num_cameras(); ++i) Stop(i);
}

// Notes when each camera's acquisition starts (its client's AcquisitionStart).
void FakeCameraServer::WatchAcquisitions() {
  while (!stop_watching_) {
    {
      std::lock_guard lock(slots_mutex_);
      for (const auto& slot : slots_) {
        const bool acquiring = slot->gv_camera != nullptr &&
                               arv_fake_camera_get_acquisition_status(
                                   arv_gv_fake_camera_get_fake_camera(slot->gv_camera)) != 0;
        if (acquiring && !slot->acquiring) slot->session_start_utime = HostUtime();
        slot->acquiring = acquiring;
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
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT, kRgb8);
  arv_fake_camera_set_trigger_frequency(fake, kTriggerPollHz);
  arv_fake_camera_set_fill_pattern(fake, &FillPattern, &slot);
  g_object_set(gv, "gvsp-lost-ratio", packet_loss_.load(), nullptr);
  std::lock_guard lock(slots_mutex_);
  slot.gv_camera = gv;
  slot.acquiring = false;
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

FrameSet FakeCameraServer::Assign(int camera, int64_t now_utime, int64_t session_start_utime) {
  std::lock_guard lock(mutex_);
  const FrameSetClock::Slot slot = clock_.Assign(camera, now_utime, session_start_utime);
  // A set joined is one of the clock's recent ones, all still in the history.
  for (auto set = history_.rbegin(); !slot.opened && set != history_.rend(); ++set) {
    if (set->seq == slot.seq) return *set;
  }
  FrameSet set;
  set.seq = slot.seq;
  set.trigger_utime = slot.first_utime;
  set.t_seconds = static_cast<double>(slot.first_utime - origin_utime_) * 1e-6;
  set.pose = PoseAt(trajectory_, set.t_seconds);
  set.scene = std::make_shared<const TubeScene>(SceneOf(trajectory_, rig_, set.pose));
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
  RenderedView view =
      slot.renderer->Render(*set.scene, trajectory_.render, static_cast<uint32_t>(Mix(noise)))[0];
  return backdrop_only_ ? view.background : view.image;
}

// Never throws: it runs inside Aravis's C thread. An image it cannot make is
// sent black and counted.
void FakeCameraServer::Fill(int camera, void* data, int width, int height, uint32_t pixel_format,
                            bool first_of_session) {
  const size_t size = static_cast<size_t>(width) * height * RawBytesPerPixel(pixel_format);
  const int64_t now = HostUtime();
  int64_t session_start = -1;
  if (first_of_session) {
    session_start = slots_[static_cast<size_t>(camera)]->session_start_utime;
    if (session_start < 0 || session_start > now) session_start = now - kFirstImageDelayUs;
  }
  try {
    const cv::Mat view = Render(camera, Assign(camera, now, session_start));
    if (EncodeRawImage(view, pixel_format, width, height, static_cast<uint8_t*>(data), size)) {
      ++images_served_;
      return;
    }
  } catch (...) {
  }
  ++errors_;
  if (size > 0) std::memset(data, 0, size);
}

}  // namespace shapesense
