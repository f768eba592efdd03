#include "services/capture/aravis_camera.h"

#include <arv.h>

#include <array>
#include <atomic>
#include <chrono>
#include <future>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <utility>
#include <vector>

#include "libs/camera/genicam_pixel_formats.h"
#include "runtime/host_clock.h"
#include "services/capture/exposure_matcher.h"

namespace shapesense {
namespace {

constexpr std::array<std::pair<const char*, uint32_t>, 7> kPixelFormats = {{
    {"Mono8", genicam::kMono8},
    {"RGB8", genicam::kRgb8},
    {"BGR8", genicam::kBgr8},
    {"BayerRG8", genicam::kBayerRg8},
    {"BayerGR8", genicam::kBayerGr8},
    {"BayerGB8", genicam::kBayerGb8},
    {"BayerBG8", genicam::kBayerBg8},
}};

// After this long without a frame, a timeout asks the device whether it is
// still there (a register read), at most once per interval.
constexpr int64_t kProbeIntervalUs = 1'000'000;

// OpenCV names a Bayer pattern by the second row's second and third pixels;
// GenICam by the first row's first two: GenICam RG is OpenCV BG, and so on.
int BayerConversion(uint32_t pixel_format) {
  switch (pixel_format) {
    case genicam::kBayerRg8:
      return cv::COLOR_BayerBG2BGR;
    case genicam::kBayerGr8:
      return cv::COLOR_BayerGB2BGR;
    case genicam::kBayerGb8:
      return cv::COLOR_BayerGR2BGR;
    case genicam::kBayerBg8:
      return cv::COLOR_BayerRG2BGR;
    default:
      return -1;
  }
}

std::string TakeMessage(GError*& error) {
  std::string message = error != nullptr ? error->message : "unknown error";
  g_clear_error(&error);
  return message;
}

ExposureMatcherOptions MatcherOptions(const CameraConfig& config) {
  ExposureMatcherOptions options;
  options.max_latency_us = static_cast<int64_t>(config.trigger_latency_us);
  options.max_exposure_delay_us = static_cast<int64_t>(config.max_exposure_delay_us);
  return options;
}

class AravisCamera final : public CameraBackend {
 public:
  explicit AravisCamera(CameraConfig config)
      : config_(std::move(config)), matcher_(MatcherOptions(config_)) {}
  ~AravisCamera() override { Close(); }
  AravisCamera(const AravisCamera&) = delete;
  AravisCamera& operator=(const AravisCamera&) = delete;

  const std::string& name() const override { return config_.name; }
  void Open() override;
  void Close() override;
  bool IsOpen() const override { return camera_ != nullptr; }
  void Trigger(int64_t seq, int64_t utime) override;
  bool Grab(std::chrono::milliseconds timeout, CameraFrame* frame) override;
  CameraStats Stats() const override;

 private:
  std::string Describe(const std::string& what) const {
    return "camera '" + config_.name + "' (aravis device '" +
           (config_.device.empty() ? std::string("first found") : config_.device) + "'): " + what;
  }
  // Throws CameraError naming the camera, the device, what failed and why.
  [[noreturn]] void Fail(const std::string& what, GError*& error) const {
    throw CameraError(Describe(what + ": " + TakeMessage(error)));
  }
  void Check(const std::string& what, GError*& error) const {
    if (error != nullptr) Fail(what, error);
  }

  ArvCamera* OpenDevice() const;
  void Configure();
  void ConfigureExposureAndGain();
  void ConfigureTrigger();
  void ConfigureTransport();
  void StartStream();
  void MarkLost(const std::string& why);
  void ThrowIfLost() const;
  void OnTimeout();
  bool TakeBuffer(ArvBuffer* buffer, CameraFrame* frame);
  static void OnControlLost(ArvDevice* device, gpointer self);

  const CameraConfig config_;
  // Releasing a lost device waits for Aravis's GVCP timeouts (about 10 s in
  // 0.8): it happens on these threads so that Close() returns at once.
  std::vector<std::future<void>> releases_;
  TriggerMode mode_ = TriggerMode::kSoftware;
  ArvCamera* camera_ = nullptr;
  ArvStream* stream_ = nullptr;
  gulong lost_handler_ = 0;
  std::atomic<bool> lost_{false};
  double exposure_us_ = 0.0;
  double gain_db_ = 0.0;
  int64_t last_alive_utime_ = 0;  // last frame or probe; Grab's thread only
  bool opened_before_ = false;

  mutable std::mutex mutex_;  // what Trigger() and Grab() share
  ExposureMatcher matcher_;
  CameraStats stats_;
  std::string lost_reason_;
};

// By Aravis device id or IP address directly; else a serial number or
// physical id (MAC) found among the devices Aravis discovers.
ArvCamera* AravisCamera::OpenDevice() const {
  const char* id = config_.device.empty() ? nullptr : config_.device.c_str();
  GError* error = nullptr;
  if (ArvCamera* camera = arv_camera_new(id, &error)) return camera;
  if (id == nullptr || g_hostname_is_ip_address(id)) Fail("cannot open the device", error);
  const std::string first_error = TakeMessage(error);
  arv_update_device_list();
  for (unsigned i = 0; i < arv_get_n_devices(); ++i) {
    for (const char* key :
         {arv_get_device_serial_nbr(i), arv_get_device_physical_id(i), arv_get_device_address(i)}) {
      if (key == nullptr || config_.device != key) continue;
      if (ArvCamera* camera = arv_camera_new(arv_get_device_id(i), &error)) return camera;
      Fail(std::string("cannot open it (found as '") + arv_get_device_id(i) + "')", error);
    }
  }
  throw CameraError(
      Describe("no device with this id, IP, serial number or MAC (" + first_error + ")"));
}

void AravisCamera::Open() {
  if (IsOpen()) Close();
  if (const std::string error = config_.Validate(); !error.empty()) {
    throw CameraError(Describe(error));
  }
  mode_ = config_.Trigger();
  camera_ = OpenDevice();
  try {
    Configure();
    StartStream();
  } catch (...) {
    Close();
    throw;
  }
  last_alive_utime_ = HostUtime();
  std::lock_guard lock(mutex_);
  if (opened_before_) ++stats_.reconnects;
  opened_before_ = true;
}

void AravisCamera::Configure() {
  GError* error = nullptr;
  arv_camera_stop_acquisition(camera_, &error);  // it may have been left running
  g_clear_error(&error);
  arv_camera_set_pixel_format_from_string(camera_, config_.pixel_format.c_str(), &error);
  Check("cannot set PixelFormat to " + config_.pixel_format, error);
  arv_camera_set_region(camera_, 0, 0, config_.width, config_.height, &error);
  Check("cannot set the image size", error);
  int x = 0, y = 0, width = 0, height = 0;
  arv_camera_get_region(camera_, &x, &y, &width, &height, &error);
  Check("cannot read the image size", error);
  if (width != config_.width || height != config_.height) {
    throw CameraError(Describe("asked for " + std::to_string(config_.width) + "x" +
                               std::to_string(config_.height) + " pixels, the device gives " +
                               std::to_string(width) + "x" + std::to_string(height)));
  }
  ConfigureExposureAndGain();
  ConfigureTrigger();
  arv_camera_set_acquisition_mode(camera_, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
  Check("cannot set AcquisitionMode to Continuous", error);
  ConfigureTransport();
}

// Both are optional features: a camera without them keeps its own.
void AravisCamera::ConfigureExposureAndGain() {
  GError* error = nullptr;
  if (arv_camera_is_exposure_time_available(camera_, nullptr)) {
    if (arv_camera_is_exposure_auto_available(camera_, nullptr)) {
      arv_camera_set_exposure_time_auto(camera_, ARV_AUTO_OFF, &error);
      Check("cannot turn automatic exposure off", error);
    }
    arv_camera_set_exposure_time(camera_, config_.exposure_us, &error);
    Check("cannot set the exposure to " + std::to_string(config_.exposure_us) + " us", error);
    exposure_us_ = arv_camera_get_exposure_time(camera_, nullptr);
  }
  if (arv_camera_is_gain_available(camera_, nullptr)) {
    if (arv_camera_is_gain_auto_available(camera_, nullptr)) {
      arv_camera_set_gain_auto(camera_, ARV_AUTO_OFF, &error);
      Check("cannot turn automatic gain off", error);
    }
    arv_camera_set_gain(camera_, config_.gain_db, &error);
    Check("cannot set the gain to " + std::to_string(config_.gain_db) + " dB", error);
    gain_db_ = arv_camera_get_gain(camera_, nullptr);
  }
}

void AravisCamera::ConfigureTrigger() {
  GError* error = nullptr;
  switch (mode_) {
    case TriggerMode::kFreeRun:
      arv_camera_clear_triggers(camera_, &error);
      Check("cannot turn the triggers off", error);
      if (arv_camera_is_frame_rate_available(camera_, nullptr)) {
        arv_camera_set_frame_rate(camera_, config_.frame_rate, &error);
        Check("cannot set the frame rate to " + std::to_string(config_.frame_rate) + " Hz", error);
      }
      return;
    case TriggerMode::kSoftware:
      arv_camera_set_trigger(camera_, "Software", &error);
      Check("cannot set a software trigger (TriggerSource Software)", error);
      return;
    case TriggerMode::kHardware:
      arv_camera_set_trigger(camera_, config_.trigger_line.c_str(), &error);
      Check("cannot trigger from line '" + config_.trigger_line + "'", error);
      return;
  }
}

// GigE Vision only: a fixed packet size (kept: no adjustment behind our
// back), or the largest one the path carries.
void AravisCamera::ConfigureTransport() {
  if (!arv_camera_is_gv_device(camera_)) return;
  GError* error = nullptr;
  if (config_.packet_size > 0) {
    arv_camera_gv_set_packet_size_adjustment(camera_, ARV_GV_PACKET_SIZE_ADJUSTMENT_NEVER);
    arv_camera_gv_set_packet_size(camera_, config_.packet_size, &error);
    Check("cannot set the packet size to " + std::to_string(config_.packet_size), error);
  } else {
    arv_camera_gv_auto_packet_size(camera_, &error);
    Check("cannot negotiate the packet size", error);
  }
}

void AravisCamera::StartStream() {
  GError* error = nullptr;
  stream_ = arv_camera_create_stream(camera_, nullptr, nullptr, &error);
  Check("cannot create the stream", error);
  if (stream_ == nullptr) throw CameraError(Describe("cannot create the stream"));
  if (arv_camera_is_gv_device(camera_) && config_.socket_buffer > 0) {
    g_object_set(stream_, "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED, "socket-buffer-size",
                 static_cast<gint>(config_.socket_buffer), nullptr);
  }
  const guint payload = arv_camera_get_payload(camera_, &error);
  Check("cannot read the payload size", error);
  for (int i = 0; i < config_.buffer_count; ++i) {
    arv_stream_push_buffer(stream_, arv_buffer_new_allocate(payload));
  }
  lost_handler_ = g_signal_connect_data(arv_camera_get_device(camera_), "control-lost",
                                        reinterpret_cast<GCallback>(&AravisCamera::OnControlLost),
                                        this, nullptr, static_cast<GConnectFlags>(0));
  arv_camera_start_acquisition(camera_, &error);
  Check("cannot start the acquisition", error);
}

void AravisCamera::Close() {
  if (camera_ == nullptr) return;
  if (lost_handler_ != 0) {
    g_signal_handler_disconnect(arv_camera_get_device(camera_), lost_handler_);
  }
  lost_handler_ = 0;
  auto release = [camera = camera_, stream = stream_] {
    if (stream != nullptr) g_object_unref(stream);
    g_object_unref(camera);
  };
  if (lost_) {
    std::erase_if(releases_, [](const std::future<void>& release_done) {
      return release_done.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
    });
    releases_.push_back(std::async(std::launch::async, release));
  } else {
    GError* error = nullptr;
    arv_camera_stop_acquisition(camera_, &error);
    g_clear_error(&error);
    release();
  }
  stream_ = nullptr;
  camera_ = nullptr;
  lost_ = false;
  std::lock_guard lock(mutex_);
  matcher_.Reset();
  lost_reason_.clear();
}

void AravisCamera::OnControlLost(ArvDevice* /*device*/, gpointer self) {
  static_cast<AravisCamera*>(self)->MarkLost("control of the device was lost (no heartbeat)");
}

void AravisCamera::MarkLost(const std::string& why) {
  std::lock_guard lock(mutex_);
  if (lost_reason_.empty()) lost_reason_ = why;
  lost_ = true;
}

void AravisCamera::ThrowIfLost() const {
  if (!lost_) return;
  std::lock_guard lock(mutex_);
  throw CameraError(Describe("device lost: " + lost_reason_));
}

// A software trigger's window opens before it leaves and closes the
// camera's latency after the camera acknowledged it (exposure_matcher.h). Hardware
// triggers are not sent from here: their frames go out with trigger_seq -1
// and their exposure stamps, and the carving service groups them by time.
void AravisCamera::Trigger(int64_t seq, int64_t utime) {
  if (!IsOpen() || lost_ || mode_ != TriggerMode::kSoftware) return;
  {
    std::lock_guard lock(mutex_);
    matcher_.Sending(seq, utime, HostUtime());
  }
  GError* error = nullptr;
  arv_camera_software_trigger(camera_, &error);
  const int64_t acked = HostUtime();
  if (error != nullptr) MarkLost("the software trigger failed: " + TakeMessage(error));
  // A trigger the camera did not acknowledge may still have reached it: its
  // window stays, so that its frame is not taken for another trigger's.
  std::lock_guard lock(mutex_);
  matcher_.Acknowledged(seq, acked);
}

bool AravisCamera::Grab(std::chrono::milliseconds timeout, CameraFrame* frame) {
  if (!IsOpen()) throw CameraError(Describe("Grab() on a closed camera"));
  const int64_t deadline = HostUtime() + timeout.count() * 1000;
  for (;;) {
    ThrowIfLost();
    const int64_t wait_us = std::max<int64_t>(0, deadline - HostUtime());
    ArvBuffer* buffer = arv_stream_timeout_pop_buffer(stream_, static_cast<guint64>(wait_us));
    if (buffer == nullptr) {
      OnTimeout();
      return false;
    }
    last_alive_utime_ = HostUtime();
    if (TakeBuffer(buffer, frame)) return true;
    if (HostUtime() >= deadline) return false;
  }
}

void AravisCamera::OnTimeout() {
  const int64_t now = HostUtime();
  {
    std::lock_guard lock(mutex_);
    ++stats_.timeouts;
    matcher_.Expire(now);
  }
  if (now - last_alive_utime_ < kProbeIntervalUs) return;
  last_alive_utime_ = now;
  guint32 value = 0;
  GError* error = nullptr;
  if (!arv_device_read_register(arv_camera_get_device(camera_), 0, &value, &error)) {
    MarkLost("the device does not answer: " + TakeMessage(error));
  }
  g_clear_error(&error);
  ThrowIfLost();
}

// Matches the buffer to its trigger (even a bad buffer answers one), converts
// a complete one into `frame`, and gives the buffer back to the stream.
bool AravisCamera::TakeBuffer(ArvBuffer* buffer, CameraFrame* frame) {
  const int64_t received_ns = static_cast<int64_t>(arv_buffer_get_system_timestamp(buffer));
  const int64_t device_ns = static_cast<int64_t>(arv_buffer_get_timestamp(buffer));
  const ExposureStamp timing{
      static_cast<int64_t>(arv_buffer_get_frame_id(buffer)), device_ns / 1000,
      received_ns != 0 ? received_ns / 1000 + TestClockOffsetUs() : HostUtime()};
  const bool complete = arv_buffer_get_status(buffer) == ARV_BUFFER_STATUS_SUCCESS;
  std::unique_lock lock(mutex_);
  matcher_.Expire(timing.received_utime);
  // An incomplete buffer's stamps may be garbage: it answers nothing.
  const std::optional<SentTrigger> trigger =
      mode_ == TriggerMode::kSoftware && complete ? matcher_.Match(timing).trigger : std::nullopt;
  cv::Mat image;
  if (complete) {
    size_t size = 0;
    const void* data = arv_buffer_get_image_data(buffer, &size);
    image =
        DecodeAravisImage(arv_buffer_get_image_pixel_format(buffer), data, size,
                          arv_buffer_get_image_width(buffer), arv_buffer_get_image_height(buffer));
  }
  const bool untriggered = mode_ == TriggerMode::kSoftware && !trigger;
  if (image.empty()) ++stats_.incomplete;
  if (!image.empty() && !untriggered) ++stats_.frames;
  lock.unlock();
  arv_stream_push_buffer(stream_, buffer);
  if (image.empty() || untriggered) return false;
  *frame = CameraFrame{image,
                       timing.frame_id,
                       trigger ? trigger->seq : -1,
                       trigger ? trigger->utime : 0,
                       device_ns,
                       HostUtime(),
                       exposure_us_,
                       gain_db_};
  return true;
}

CameraStats AravisCamera::Stats() const {
  std::lock_guard lock(mutex_);
  CameraStats stats = stats_;
  stats.missed_triggers = matcher_.unanswered();
  stats.unmatched_frames = matcher_.rejected();
  stats.unmatched_reasons = matcher_.DescribeRejections();
  return stats;
}

}  // namespace

std::unique_ptr<CameraBackend> MakeAravisCamera(const CameraConfig& config) {
  return std::make_unique<AravisCamera>(config);
}

cv::Mat DecodeAravisImage(uint32_t pixel_format, const void* data, size_t size, int width,
                          int height) {
  const int bayer = BayerConversion(pixel_format);
  const bool colour = pixel_format == genicam::kRgb8 || pixel_format == genicam::kBgr8;
  if (data == nullptr || width <= 0 || height <= 0) return {};
  if (!colour && pixel_format != genicam::kMono8 && bayer < 0) return {};
  if (size < static_cast<size_t>(width) * height * (colour ? 3 : 1)) return {};
  // A view of the buffer (not written); every branch copies out of it.
  const cv::Mat raw(height, width, colour ? CV_8UC3 : CV_8UC1, const_cast<void*>(data));
  cv::Mat image;
  if (pixel_format == genicam::kRgb8) {
    cv::cvtColor(raw, image, cv::COLOR_RGB2BGR);
  } else if (bayer >= 0) {
    cv::cvtColor(raw, image, bayer);
  } else {
    raw.copyTo(image);
  }
  return image;
}

uint32_t AravisPixelFormatCode(const std::string& name) {
  for (const auto& [format_name, code] : kPixelFormats) {
    if (name == format_name) return code;
  }
  return 0;
}

}  // namespace shapesense
