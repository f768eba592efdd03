#pragma once

// One interface for every camera the capture service can read: Aravis
// (GigE Vision / USB3 Vision), V4L2, replay of a dataset or video, and the
// virtual rig's in-process renderer. Chosen by CameraConfig::backend.

#include <chrono>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

namespace shapesense {

// A camera that cannot be opened, was lost, or is misconfigured. The message
// names the camera and what went wrong.
class CameraError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class TriggerMode {
  kFreeRun,   // the camera runs at its frame rate
  kSoftware,  // one exposure per Trigger() call; all cameras of a frame-set triggered together
  kHardware,  // an external line triggers every camera
};

struct CameraConfig {
  std::string name;                // as in the rig file
  std::string backend = "aravis";  // aravis | v4l2 | replay | simulated
  // aravis: device id, serial number or IP address; v4l2: /dev/videoN;
  // replay: dataset folder or video file; simulated: (unused).
  std::string device;
  // aravis: Mono8 | RGB8 | BayerRG8 | BayerGR8 | BayerGB8 | BayerBG8;
  // v4l2: YUYV | MJPG | RGB3 | BGR3 (fourcc).
  std::string pixel_format = "RGB8";
  int width = 640;
  int height = 480;
  double exposure_us = 5000.0;
  double gain_db = 0.0;
  double frame_rate = 30.0;            // Hz: free run, replay rate
  std::string trigger = "software";    // free_run | software | hardware
  std::string trigger_line = "Line1";  // hardware trigger source
  // Where the camera's timestamps come from: "ptp" (IEEE 1588-synchronised
  // with the host's clock, or the virtual rig's cameras, on the host's
  // clock): triggered frames are matched to their trigger by exposure time.
  std::string timestamp_clock = "ptp";
  double trigger_latency_us = 4000.0;      // longest trigger -> exposure start
  double max_exposure_delay_us = 10000.0;  // longest frame-set time -> exposure start
  int packet_size = 0;                     // GigE packet size, bytes (0: negotiate)
  int socket_buffer = 0;                   // GigE socket buffer, bytes (0: Aravis default)
  int buffer_count = 8;                    // stream / mmap buffers
  bool loop = true;                        // replay: start again at the end

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("name", name, "camera name, as in the rig file");
    visit("backend", backend, "aravis | v4l2 | replay | simulated");
    visit("device", device, "aravis: id, serial or IP; v4l2: /dev/videoN; replay: folder or video");
    visit("pixel_format", pixel_format,
          "aravis: Mono8, RGB8, Bayer??8; v4l2: YUYV, MJPG, RGB3, BGR3");
    visit("width", width, "image width, px");
    visit("height", height, "image height, px");
    visit("exposure_us", exposure_us, "exposure, µs");
    visit("gain_db", gain_db, "gain, dB");
    visit("frame_rate", frame_rate, "frame rate in free run and replay, Hz");
    visit("trigger", trigger, "free_run | software | hardware");
    visit("trigger_line", trigger_line, "hardware trigger input (e.g. Line1)");
    visit("timestamp_clock", timestamp_clock,
          "aravis: ptp (device timestamps on the host's clock; docs/capture.md)");
    visit("trigger_latency_us", trigger_latency_us,
          "aravis: longest time from a trigger's receipt to its exposure, µs (1-100000)");
    visit("max_exposure_delay_us", max_exposure_delay_us,
          "aravis: a frame exposed later after its frame-set's time is dropped, µs (1-1000000)");
    visit("packet_size", packet_size, "GigE packet size, bytes (0: negotiate)");
    visit("socket_buffer", socket_buffer, "GigE socket buffer, bytes (0: default)");
    visit("buffer_count", buffer_count, "stream buffers (2-64)");
    visit("loop", loop, "replay: loop at the end");
  }
  std::string Validate() const;
  TriggerMode Trigger() const;
};

// One image as the camera delivered it, converted to 8-bit BGR (or mono).
struct CameraFrame {
  cv::Mat image;                    // CV_8UC3 BGR or CV_8UC1
  int64_t frame_id = 0;             // the camera's own counter
  int64_t trigger_seq = -1;         // frame-set sequence; -1 in free run
  int64_t trigger_utime = 0;        // trigger time, µs since epoch (host clock)
  int64_t device_timestamp_ns = 0;  // camera clock; 0 when unknown
  int64_t host_utime = 0;           // complete image received, µs since epoch
  double exposure_us = 0.0;
  double gain_db = 0.0;
};

struct CameraStats {
  int64_t frames = 0;      // complete frames delivered
  int64_t incomplete = 0;  // incomplete or corrupted buffers dropped
  int64_t timeouts = 0;
  int64_t reconnects = 0;
  // Triggers that got no frame (the camera missed them, or their frame was
  // lost or dropped): frame-sets this camera will miss.
  int64_t missed_triggers = 0;
  // Frames dropped because nothing proves which trigger they answer, and why
  // (e.g. "2 frames exposed outside every trigger's window").
  int64_t unmatched_frames = 0;
  std::string unmatched_reasons;
};

// Threads (as the capture service uses it): Open, Close and Grab come from
// the camera's grab thread; Trigger from the trigger thread while Grab may be
// waiting (never during Open or Close); Stats from the status thread at any
// time. A backend makes Trigger and Stats safe against the others.
class CameraBackend {
 public:
  virtual ~CameraBackend() = default;

  virtual const std::string& name() const = 0;
  // Opens and configures the device and starts acquisition; CameraError on failure.
  virtual void Open() = 0;
  virtual void Close() = 0;
  virtual bool IsOpen() const = 0;
  // Software trigger: one exposure for frame-set `seq`, triggered at `utime`.
  virtual void Trigger(int64_t seq, int64_t utime) = 0;
  // Waits up to `timeout` for the next complete frame; false on timeout.
  // Throws CameraError when the device is lost (the caller reopens it later).
  virtual bool Grab(std::chrono::milliseconds timeout, CameraFrame* frame) = 0;
  virtual CameraStats Stats() const = 0;
};

// Parses a command-line camera spec "NAME=BACKEND:DEVICE", e.g.
// "cam0=aravis:127.0.0.1" or "cam1=v4l2:/dev/video0". Throws std::invalid_argument.
// The other keys keep their defaults, but for the backend's pixel format
// (DefaultPixelFormat).
CameraConfig ParseCameraSpec(const std::string& spec);

// The pixel format a camera of `backend` uses when none is given: YUYV for
// v4l2 (what every UVC camera offers), RGB8 otherwise.
std::string DefaultPixelFormat(const std::string& backend);

}  // namespace shapesense
