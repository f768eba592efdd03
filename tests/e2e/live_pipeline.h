#pragma once

// The live pipeline as separate programs, for the end-to-end tests: the
// virtual rig (shapesense-rig-sim, three fake GigE Vision cameras),
// shapesense-capture on them over Aravis, shapesense-carving and
// shapesense-shape, all on UDP multicast LCM inside the test's private
// network namespace (tests/support), and a recorder in the test process that
// subscribes to the truth, the shapes and every service's status.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "libs/camera/camera.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/process/child_process.h"
#include "runtime/process/virtual_hosts.h"
#include "shapesense/service_status_t.hpp"
#include "shapesense/shape_t.hpp"

namespace shapesense::e2e {

// LCM inside the namespace; receivers of images need a larger socket buffer
// (docs/capture.md, "Large images on LCM").
inline constexpr const char* kLcmUrl = "udpm://239.255.76.67:7667?ttl=0";
std::string ReceiverUrl();

// Sanitizer builds run everything about three times slower: a lower trigger
// rate there (the Release tests keep 30 Hz).
bool UnderSanitizers();
// The rig's trigger rate in the live tests: 30 Hz. Under AddressSanitizer
// and UBSan every process is several times slower, the rig-sim's rendering
// too, and at 10 Hz its cameras already answered late and the capture
// service dropped frame-sets on this 2-core machine: 5 Hz there.
double LiveRate();

// A copy of the folder `config` in `copy` whose controller holds after 0.6 s
// without sensing and stops after 3 s: sensing at 5 Hz, seconds late, under
// sanitizers.
std::filesystem::path ConfigWithSlowerWatchdog(const std::filesystem::path& config,
                                               const std::filesystem::path& copy);

// A message as it arrived at the test.
template <class Message>
struct Received {
  Message message;
  int64_t receive_utime = 0;
};

// Truths, shapes and statuses, gathered on a thread of its own.
class Recorder {
 public:
  explicit Recorder(const std::string& url = ReceiverUrl());
  explicit Recorder(const LcmBusOptions& options);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  std::vector<shape_t> Truths() const;
  std::vector<Received<shape_t>> Shapes() const;
  size_t ShapeCount() const;
  // The last status of a service ("capture", "carving", "shape", "rig_sim").
  std::optional<service_status_t> LastStatus(const std::string& service) const;
  // Every status of a service, oldest first.
  std::vector<service_status_t> StatusHistory(const std::string& service) const;
  int64_t Rejected() const { return bus_.Rejected(); }

  // Waits (bounded) until `done` holds; false on timeout.
  bool WaitFor(const std::function<bool()>& done, std::chrono::milliseconds timeout) const;
  // Waits for a status of `service` published after `after_utime`.
  std::optional<service_status_t> WaitForStatus(const std::string& service, int64_t after_utime,
                                                std::chrono::milliseconds timeout) const;

 private:
  LcmBus bus_;
  mutable std::mutex mutex_;
  std::vector<shape_t> truths_;
  std::vector<Received<shape_t>> shapes_;
  std::map<std::string, std::vector<service_status_t>> statuses_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

struct PipelineOptions {
  double rate_hz = 30.0;
  uint32_t seed = 5;
  std::vector<std::string> rig_sim_args;  // e.g. --packet-loss 0.05
  // Carving and shape service assembly and pairing timeouts, ms: generous,
  // so that a loaded test machine's scheduling is not taken for a loss.
  double assembly_timeout_ms = 1000.0;
  int queue_capacity = 8;
  // The cameras' pixel format and GigE packet size, bytes.
  std::string pixel_format = "RGB8";
  int packet_size = 16384;
  // The synthetic rig's image size (its focal length scaled with it).
  int image_width = 640;
  int image_height = 480;
  // Two hosts (runtime/process/virtual_hosts.h) instead of one: the rig-sim,
  // capture, carving and this test's recorder on kCameraHost, the shape
  // service on kShapeHost, the rig network between them (kRigUrl, ttl=1)
  // and the images on the camera host's local network. Null: one host.
  const VirtualHosts* hosts = nullptr;
};

// The hosts of a two-host pipeline, and its rig network.
inline constexpr const char* kCameraHost = "camera";
inline constexpr const char* kShapeHost = "shape";
inline constexpr const char* kRigUrl = "udpm://239.255.77.1:7701?ttl=1&recv_buf_size=4194304";

// The programs of one run, in a folder of their own; every process is
// stopped when the run goes away.
class LivePipeline {
 public:
  explicit LivePipeline(const std::string& name, PipelineOptions options = {});
  ~LivePipeline();

  const std::filesystem::path& dir() const { return dir_; }
  Recorder& recorder() { return *recorder_; }
  const Rig& rig() const { return rig_; }

  // Starts the rig-sim, writes the rig, backgrounds and service configs,
  // starts the carving and shape services and waits until both report.
  // Returns "" or what failed.
  std::string StartServices();
  // Starts lcm-logger on every channel of the rig's bus into `log`, and one
  // per camera's image port into ImageLogs(log); "" or what failed.
  std::string StartLogger(const std::filesystem::path& log);
  // The image logs StartLogger writes beside `log`: <stem>_<camera>.lcmlog.
  std::vector<std::filesystem::path> ImageLogs(const std::filesystem::path& log) const;
  // Runs the capture service for `seconds` and waits for it to end; returns
  // "" or what failed. Sets capture_start_utime/capture_end_utime.
  std::string RunCapture(double seconds);
  // Starts the capture service without waiting (for faults during a run).
  void StartCapture(double seconds);
  // Waits for the capture started by StartCapture to end; "" or what failed.
  std::string WaitForCapture(double seconds);
  // Waits until no shape has arrived for `quiet` and the carving and shape
  // services have reported after that.
  void Drain(std::chrono::milliseconds quiet = std::chrono::milliseconds(1500));
  // Stops every process; returns "" or which did not stop cleanly.
  std::string StopAll();

  ChildProcess& rig_sim() { return *rig_sim_; }
  ChildProcess& shape_service() { return *shape_; }

  int64_t capture_start_utime() const { return capture_start_utime_; }
  int64_t capture_end_utime() const { return capture_end_utime_; }
  std::filesystem::path CarvingConfig() const { return dir_ / "carving.yaml"; }
  std::filesystem::path ShapeConfig() const { return dir_ / "shape.yaml"; }
  // The rig key of a run on two hosts.
  std::filesystem::path KeyFile() const { return dir_ / "rig.key"; }

 private:
  std::filesystem::path WriteSmallerRig() const;
  void WriteRigFiles();
  void WriteCaptureConfig();
  std::unique_ptr<ChildProcess> StartService(const std::string& binary,
                                             const std::filesystem::path& config,
                                             const std::string& host);
  // Where a program runs: its host's namespace, name, clock and networks.
  ChildOptions On(const std::string& host) const;
  // The URL every program is given: the rig network (two hosts) or the one bus.
  std::string BusUrl(bool receives_images) const;

  PipelineOptions options_;
  std::filesystem::path dir_;
  Rig rig_;
  std::unique_ptr<Recorder> recorder_;
  std::unique_ptr<ChildProcess> rig_sim_;
  std::unique_ptr<ChildProcess> carving_;
  std::unique_ptr<ChildProcess> shape_;
  std::unique_ptr<ChildProcess> capture_;
  std::vector<std::unique_ptr<ChildProcess>> loggers_;
  int64_t capture_start_utime_ = 0;
  int64_t capture_end_utime_ = 0;
};

// One measured shape and the truth it was paired with.
struct ScoredShape {
  shape_t shape;
  std::optional<shape_t> truth;    // none: no truth within the tolerance
  double centerline_rms_mm = 0.0;  // measured centreline to the true one
};

struct Score {
  int truths = 0;         // frame-sets the rig-sim rendered (before the end margin)
  int shapes = 0;         // shapes received
  int valid = 0;          // valid shapes
  int matched = 0;        // valid shapes paired with a truth
  int unmeasured = 0;     // truths (before the end margin) no valid shape was paired with
  double rms_mean = 0.0;  // mm, over the matched shapes
  double rms_max = 0.0;
  std::vector<ScoredShape> scored;
  std::vector<int64_t> unmeasured_times;  // trigger times of the unmeasured truths
};

// Pairs every shape with the truth of the same frame-set: the truth's
// trigger time is when the set's first trigger reached the rig-sim, a little
// after the capture service sent it, so the pair is the first truth at or
// after the shape's trigger time within `tolerance_us`. Truths after
// `end_utime` (sets the capture service was stopping during) are not counted.
Score ScoreShapes(const std::vector<shape_t>& truths, const std::vector<Received<shape_t>>& shapes,
                  int64_t end_utime, int64_t tolerance_us);

std::string Describe(const Score& score);
std::string Describe(const service_status_t& status);
// The shapes over `rms_mm` from their truth, or without one, one a line.
std::string BadShapes(const Score& score, double rms_mm);
// The score and each service's last status, for the test's output.
std::string Report(const Score& score, const Recorder& recorder);

// How long a truth may trail its shape's trigger time, µs (live_pipeline.cc).
int64_t PairingToleranceUs(double rate_hz);

// What the capture service's last status says its dropped frame-sets were,
// summed over the cameras (services/capture/capture_service.cc).
struct CaptureDrops {
  int64_t incomplete = 0;  // images that arrived broken
  int64_t unanswered = 0;  // triggers the camera answered with no image
  int64_t not_sent = 0;    // triggers not sent (camera down, busy or too late)
  int64_t total() const { return incomplete + unanswered + not_sent; }
};
CaptureDrops ParseCaptureDrops(const std::string& last_error);

}  // namespace shapesense::e2e
