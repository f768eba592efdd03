#include "services/capture/camera_backend.h"

#include "libs/core/error.h"

#include <algorithm>
#include <array>
#include <sstream>
#include <stdexcept>

namespace shapesense {
namespace {

constexpr std::array<const char*, 4> kBackends = {"aravis", "v4l2", "replay", "simulated"};
constexpr std::array<const char*, 6> kAravisFormats = {"Mono8",    "RGB8",     "BayerRG8",
                                                       "BayerGR8", "BayerGB8", "BayerBG8"};
constexpr std::array<const char*, 5> kV4l2Formats = {"YUYV", "MJPG", "MJPEG", "RGB3", "BGR3"};
// Replay and simulated images are colour (delivered BGR) or converted to mono.
constexpr std::array<const char*, 3> kImageFormats = {"RGB8", "BGR8", "Mono8"};
constexpr std::array<const char*, 3> kTriggers = {"free_run", "software", "hardware"};

template <size_t N>
bool OneOf(const std::string& value, const std::array<const char*, N>& choices) {
  return std::any_of(choices.begin(), choices.end(),
                     [&](const char* choice) { return value == choice; });
}

template <size_t N>
std::string Choices(const std::array<const char*, N>& choices) {
  std::string out;
  for (size_t i = 0; i < N; ++i)
    out += (i == 0 ? "" : (i + 1 == N ? " or " : ", ")) + std::string(choices[i]);
  return out;
}

std::string Quoted(const std::string& text) { return "'" + text + "'"; }

// Names end up in LCM channel names and file names.
bool IsPlainName(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-';
  });
}

std::string ValidatePixelFormat(const CameraConfig& config) {
  if (config.backend == "aravis" && !OneOf(config.pixel_format, kAravisFormats)) {
    return Expected("pixel_format", "for aravis " + Choices(kAravisFormats),
                    Quoted(config.pixel_format));
  }
  if (config.backend == "v4l2" && !OneOf(config.pixel_format, kV4l2Formats)) {
    return Expected("pixel_format", "for v4l2 " + Choices(kV4l2Formats),
                    Quoted(config.pixel_format));
  }
  if ((config.backend == "replay" || config.backend == "simulated") &&
      !OneOf(config.pixel_format, kImageFormats)) {
    return Expected("pixel_format", "for " + config.backend + " " + Choices(kImageFormats),
                    Quoted(config.pixel_format));
  }
  return "";
}

std::string ValidateDevice(const CameraConfig& config) {
  if (config.backend == "v4l2" && config.device.empty()) {
    return Expected("device", "a V4L2 device path such as /dev/video0", "''");
  }
  if (config.backend == "replay" && config.device.empty()) {
    return Expected("device", "a dataset folder or a video file", "''");
  }
  return "";
}

std::string ValidateTrigger(const CameraConfig& config) {
  if (!OneOf(config.trigger, kTriggers)) {
    return Expected("trigger", Choices(kTriggers), Quoted(config.trigger));
  }
  if (config.trigger == "hardware" && config.backend != "aravis") {
    return Expected(
        "trigger",
        "free_run or software for " + config.backend + " (only aravis cameras have trigger lines)",
        Quoted(config.trigger));
  }
  if (config.trigger == "hardware" && config.trigger_line.empty()) {
    return Expected("trigger_line", "a trigger input such as Line1", "''");
  }
  // Only a clock shared with the host proves which trigger a frame answers.
  if (config.timestamp_clock != "ptp") {
    return Expected("timestamp_clock",
                    "ptp (triggered frames are matched by exposure time on the host's clock; "
                    "docs/capture.md)",
                    Quoted(config.timestamp_clock));
  }
  if (!(config.trigger_latency_us >= 1.0 && config.trigger_latency_us <= 100'000.0)) {
    return Expected("trigger_latency_us", "1-100000 µs", config.trigger_latency_us);
  }
  if (!(config.max_exposure_delay_us >= 1.0 && config.max_exposure_delay_us <= 1e6)) {
    return Expected("max_exposure_delay_us", "1-1000000 µs", config.max_exposure_delay_us);
  }
  return "";
}

std::string ValidateNumbers(const CameraConfig& c) {
  if (c.width < 1 || c.width > 16384) return Expected("width", "1-16384 px", c.width);
  if (c.height < 1 || c.height > 16384) return Expected("height", "1-16384 px", c.height);
  if (!(c.exposure_us > 0.0) || c.exposure_us > 1e7) {
    return Expected("exposure_us", "a positive exposure up to 1e7 µs", c.exposure_us);
  }
  if (!(c.gain_db >= 0.0) || c.gain_db > 60.0) return Expected("gain_db", "0-60 dB", c.gain_db);
  if (!(c.frame_rate > 0.0) || c.frame_rate > 1000.0) {
    return Expected("frame_rate", "a rate in (0, 1000] Hz", c.frame_rate);
  }
  if (c.packet_size != 0 && (c.packet_size < 576 || c.packet_size > 16384)) {
    return Expected("packet_size", "0 (negotiate) or 576-16384 bytes", c.packet_size);
  }
  if (c.socket_buffer < 0)
    return Expected("socket_buffer", "0 (default) or more bytes", c.socket_buffer);
  if (c.buffer_count < 2 || c.buffer_count > 64) {
    return Expected("buffer_count", "2-64 buffers", c.buffer_count);
  }
  return "";
}

}  // namespace

std::string CameraConfig::Validate() const {
  if (!IsPlainName(name)) {
    return Expected("name", "a non-empty name of letters, digits, '_' or '-'", Quoted(name));
  }
  if (!OneOf(backend, kBackends)) return Expected("backend", Choices(kBackends), Quoted(backend));
  for (const std::string& error : {ValidateDevice(*this), ValidatePixelFormat(*this),
                                   ValidateTrigger(*this), ValidateNumbers(*this)}) {
    if (!error.empty()) return error;
  }
  return "";
}

TriggerMode CameraConfig::Trigger() const {
  if (trigger == "free_run") return TriggerMode::kFreeRun;
  if (trigger == "software") return TriggerMode::kSoftware;
  if (trigger == "hardware") return TriggerMode::kHardware;
  throw std::invalid_argument(Expected("trigger", Choices(kTriggers), Quoted(trigger)));
}

std::string DefaultPixelFormat(const std::string& backend) {
  return backend == "v4l2" ? "YUYV" : "RGB8";
}

CameraConfig ParseCameraSpec(const std::string& spec) {
  const std::string usage = "--camera " + Quoted(spec) +
                            ": expected NAME=BACKEND:DEVICE (e.g. cam0=aravis:127.0.0.1, "
                            "cam1=v4l2:/dev/video0, cam2=replay:/data/set, cam3=simulated:)";
  const size_t equals = spec.find('=');
  const size_t colon = equals == std::string::npos ? std::string::npos : spec.find(':', equals);
  if (equals == std::string::npos || colon == std::string::npos) throw std::invalid_argument(usage);
  CameraConfig config;
  config.name = spec.substr(0, equals);
  config.backend = spec.substr(equals + 1, colon - equals - 1);
  config.device = spec.substr(colon + 1);
  config.pixel_format = DefaultPixelFormat(config.backend);
  if (const std::string error = config.Validate(); !error.empty()) {
    throw std::invalid_argument("--camera " + Quoted(spec) + ": " + error);
  }
  return config;
}

}  // namespace shapesense
