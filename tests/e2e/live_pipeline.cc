#include "tests/e2e/live_pipeline.h"

#include <unistd.h>

#include <algorithm>
#include <regex>
#include <sstream>

#include "libs/camera/rig_yaml.h"
#include "libs/config/options_yaml.h"
#include "libs/control/control_options.h"
#include "libs/geometry/polyline.h"
#include "libs/sim/scene_generators.h"
#include "libs/sim/trajectory.h"
#include "runtime/dataset.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/image_buses.h"
#include "runtime/security/key_file.h"
#include "services/carving/carving_service.h"
#include "services/shape/shape_service.h"

namespace shapesense::e2e {
namespace fs = std::filesystem;
using std::chrono::milliseconds;
using Clock = std::chrono::steady_clock;

namespace {

// Every process gets a bound of its own, so that nothing outlives a test
// that died: seconds.
constexpr const char* kProcessBound = "300";

// The rig-sim's cameras and the capture service's triggers stand for
// hardware and a real-time process: they run ahead of the rest where the
// test may raise their priority (as root), so that another load on the
// machine delays the measuring, not the cameras. Elsewhere nice says so
// on standard error and runs them as they are.
constexpr const char* kNice = "/usr/bin/nice";

Polyline ToPolyline(const std::vector<std::vector<double>>& points) {
  Polyline out;
  for (const auto& p : points) {
    if (p.size() == 3) out.emplace_back(p[0], p[1], p[2]);
  }
  return out;
}

}  // namespace

std::string ReceiverUrl() { return std::string(kLcmUrl) + "&recv_buf_size=4194304"; }

bool UnderSanitizers() {
#if defined(__SANITIZE_ADDRESS__)
  return true;
#else
  return false;
#endif
}

double LiveRate() { return UnderSanitizers() ? 5.0 : 30.0; }

fs::path ConfigWithSlowerWatchdog(const fs::path& config, const fs::path& copy) {
  fs::create_directories(copy);
  for (const fs::directory_entry& entry : fs::directory_iterator(config)) {
    if (entry.path().extension() == ".yaml")
      fs::copy_file(entry.path(), copy / entry.path().filename());
  }
  ControllerOptions options =
      ParseControllerYaml(ReadTextFile(copy / "controller.yaml"), "controller.yaml");
  options.watchdog.hold_age = 0.6;
  options.watchdog.lost_age = 3.0;
  WriteFileAtomically(copy / "controller.yaml", OptionsToDocumentedYaml(options));
  return copy;
}

Recorder::Recorder(const std::string& url) : Recorder(LcmBusOptions::FromEnvironment(url)) {}

Recorder::Recorder(const LcmBusOptions& options) : bus_(options) {
  bus_.Subscribe<shape_t>(channels::kTruth,
                          [this](const shape_t& truth, const std::string&, int64_t) {
                            std::lock_guard lock(mutex_);
                            truths_.push_back(truth);
                          });
  bus_.Subscribe<shape_t>(channels::kShape,
                          [this](const shape_t& shape, const std::string&, int64_t utime) {
                            std::lock_guard lock(mutex_);
                            shapes_.push_back({shape, utime});
                          });
  bus_.Subscribe<service_status_t>(channels::kStatusPattern, [this](const service_status_t& status,
                                                                    const std::string&, int64_t) {
    std::lock_guard lock(mutex_);
    statuses_[status.service].push_back(status);
  });
  thread_ = std::thread([this] {
    while (!stop_) bus_.Handle(20);
  });
}

Recorder::~Recorder() {
  stop_ = true;
  thread_.join();
}

std::vector<shape_t> Recorder::Truths() const {
  std::lock_guard lock(mutex_);
  return truths_;
}

std::vector<Received<shape_t>> Recorder::Shapes() const {
  std::lock_guard lock(mutex_);
  return shapes_;
}

size_t Recorder::ShapeCount() const {
  std::lock_guard lock(mutex_);
  return shapes_.size();
}

std::optional<service_status_t> Recorder::LastStatus(const std::string& service) const {
  std::lock_guard lock(mutex_);
  const auto it = statuses_.find(service);
  if (it == statuses_.end() || it->second.empty()) return std::nullopt;
  return it->second.back();
}

std::vector<service_status_t> Recorder::StatusHistory(const std::string& service) const {
  std::lock_guard lock(mutex_);
  const auto it = statuses_.find(service);
  return it == statuses_.end() ? std::vector<service_status_t>{} : it->second;
}

bool Recorder::WaitFor(const std::function<bool()>& done, milliseconds timeout) const {
  const auto end = Clock::now() + timeout;
  while (!done()) {
    if (Clock::now() > end) return false;
    std::this_thread::sleep_for(milliseconds(20));
  }
  return true;
}

std::optional<service_status_t> Recorder::WaitForStatus(const std::string& service,
                                                        int64_t after_utime,
                                                        milliseconds timeout) const {
  std::optional<service_status_t> status;
  WaitFor(
      [&] {
        status = LastStatus(service);
        return status && status->header.utime > after_utime;
      },
      timeout);
  if (status && status->header.utime > after_utime) return status;
  return std::nullopt;
}

LivePipeline::LivePipeline(const std::string& name, PipelineOptions options)
    : options_(std::move(options)),
      dir_(fs::temp_directory_path() /
           ("shapesense_e2e_" + name + "_" + std::to_string(getpid()))) {
  fs::remove_all(dir_);
  fs::create_directories(dir_);
  if (options_.hosts == nullptr) {
    recorder_ = std::make_unique<Recorder>();
    return;
  }
  // The rig network crosses hosts: every program holds the rig key, as a
  // rig's hosts do (docs/security.md).
  WriteKeyFile(KeyFile(), NewAuthKey(1));
  // The recorder's sockets and threads belong to the camera host: made by
  // a thread that has entered it.
  std::thread([this] {
    options_.hosts->EnterFromThisThread(kCameraHost);
    LcmBusOptions bus;
    bus.url = kRigUrl;
    bus.local_url = ReceiverUrl();
    bus.auth.key_files = {KeyFile()};
    recorder_ = std::make_unique<Recorder>(bus);
  }).join();
}

ChildOptions LivePipeline::On(const std::string& host) const {
  ChildOptions options;
  if (options_.hosts == nullptr) return options;
  options_.hosts->PlaceOn(host, &options);
  options.environment.emplace_back("SHAPESENSE_LOCAL_LCM_URL", ReceiverUrl());
  options.environment.emplace_back("SHAPESENSE_KEY_FILES", KeyFile().string());
  return options;
}

std::string LivePipeline::BusUrl(bool receives_images) const {
  if (options_.hosts != nullptr) return kRigUrl;
  return receives_images ? ReceiverUrl() : kLcmUrl;
}

LivePipeline::~LivePipeline() {
  StopAll();
  recorder_.reset();
  std::error_code ignored;
  fs::remove_all(dir_, ignored);
}

// The rig-sim's synthetic rig with other image sizes.
fs::path LivePipeline::WriteSmallerRig() const {
  SyntheticRigOptions rig;
  rig.seed = options_.seed;
  rig.focal_px *= static_cast<double>(options_.image_width) / rig.image_width;
  rig.image_width = options_.image_width;
  rig.image_height = options_.image_height;
  fs::path path = dir_ / "synthetic_rig.yaml";
  WriteFileAtomically(path, FormatRigYaml(MakeSyntheticRig(rig)));
  return path;
}

// The rig the rig-sim wrote, its backdrop rendered as the backgrounds (the
// same renderer and options the rig-sim's cameras use, other noise), and the
// two services' configs.
void LivePipeline::WriteRigFiles() {
  rig_ = ParseRigYaml(ReadTextFile(dir_ / "rig_sim_rig.yaml"), "rig_sim_rig.yaml");
  const TrajectoryOptions trajectory;
  std::vector<cv::Mat> backgrounds;
  for (const RenderedView& view :
       SceneRenderer(rig_).Render(SceneAt(trajectory, rig_, 0.0), trajectory.render, 99)) {
    backgrounds.push_back(view.background);
  }
  WriteDatasetHeader(dir_ / "rig", rig_, backgrounds);
  CarvingServiceOptions carving;
  carving.rig = "rig/rig.yaml";
  carving.backgrounds = "rig/background";
  carving.assembly.timeout_ms = options_.assembly_timeout_ms;
  carving.queue_capacity = options_.queue_capacity;
  WriteFileAtomically(CarvingConfig(), OptionsToDocumentedYaml(carving));
  ShapeServiceOptions shape;
  shape.rig = carving.rig;
  shape.pairing_timeout_ms = 2 * options_.assembly_timeout_ms;
  shape.queue_capacity = options_.queue_capacity;
  WriteFileAtomically(ShapeConfig(), OptionsToDocumentedYaml(shape));
}

std::unique_ptr<ChildProcess> LivePipeline::StartService(const std::string& binary,
                                                         const fs::path& config,
                                                         const std::string& host) {
  return std::make_unique<ChildProcess>(
      std::vector<std::string>{binary, "--config", config.string(), "--lcm-url", BusUrl(true),
                               "--duration", kProcessBound},
      On(host));
}

std::string LivePipeline::StartServices() {
  std::vector<std::string> argv = {kNice,         "-n",
                                   "-10",         E2E_RIG_SIM,
                                   "--lcm-url",   BusUrl(false),
                                   "--seed",      std::to_string(options_.seed),
                                   "--write-rig", (dir_ / "rig_sim_rig.yaml").string(),
                                   "--duration",  kProcessBound};
  argv.insert(argv.end(), options_.rig_sim_args.begin(), options_.rig_sim_args.end());
  if (options_.image_width != SyntheticRigOptions{}.image_width) {
    argv.push_back("--rig");
    argv.push_back(WriteSmallerRig().string());
  }
  rig_sim_ = std::make_unique<ChildProcess>(argv, On(kCameraHost));
  if (!rig_sim_->WaitForLine("rig-sim: ready", milliseconds(30000))) {
    return "the rig-sim did not start: " + rig_sim_->output();
  }
  WriteRigFiles();
  const int64_t started = NowUtime();
  carving_ = StartService(E2E_CARVING, CarvingConfig(), kCameraHost);
  shape_ = StartService(E2E_SHAPE, ShapeConfig(), kShapeHost);
  // A service reports once its table is built and it listens.
  for (const char* service : {"carving", "shape"}) {
    if (!recorder_->WaitForStatus(service, started, milliseconds(120000))) {
      return std::string("the ") + service + " service never reported its status";
    }
  }
  return {};
}

std::vector<fs::path> LivePipeline::ImageLogs(const fs::path& log) const {
  std::vector<fs::path> logs;
  for (const Camera& camera : rig_.cameras) {
    logs.push_back(log.parent_path() / (log.stem().string() + "_" + camera.name + ".lcmlog"));
  }
  return logs;
}

std::string LivePipeline::StartLogger(const fs::path& log) {
  std::vector<std::pair<std::string, fs::path>> to_log = {{ReceiverUrl(), log}};
  const std::vector<fs::path> image_logs = ImageLogs(log);
  for (size_t k = 0; k < image_logs.size(); ++k) {
    to_log.emplace_back(ImageUrl(ReceiverUrl(), k), image_logs[k]);
  }
  for (const auto& url_and_log : to_log) {
    const fs::path& path = url_and_log.second;
    loggers_.push_back(std::make_unique<ChildProcess>(
        std::vector<std::string>{"/usr/bin/lcm-logger", "--lcm-url=" + url_and_log.first, "--force",
                                 "--quiet", path.string()}));
    // lcm-logger prints nothing when quiet: wait for its file.
    if (!recorder_->WaitFor([&] { return fs::exists(path); }, milliseconds(10000))) {
      return "lcm-logger did not create " + path.string();
    }
  }
  return {};
}

// The rig's cameras on the rig-sim's addresses, with a fixed GigE packet
// size (Aravis negotiates 1500 bytes on loopback: 600 packets an image).
void LivePipeline::WriteCaptureConfig() {
  std::string yaml = "cameras:\n";
  for (size_t i = 0; i < rig_.cameras.size(); ++i) {
    const Camera& camera = rig_.cameras[i];
    yaml += "  - {name: " + camera.name + ", backend: aravis, device: 127.0.0." +
            std::to_string(i + 1) + ", pixel_format: " + options_.pixel_format +
            ", width: " + std::to_string(camera.width) +
            ", height: " + std::to_string(camera.height) +
            ", packet_size: " + std::to_string(options_.packet_size) + "}\n";
  }
  WriteFileAtomically(dir_ / "capture.yaml", yaml);
}

void LivePipeline::StartCapture(double seconds) {
  WriteCaptureConfig();
  capture_start_utime_ = NowUtime();
  capture_ = std::make_unique<ChildProcess>(
      std::vector<std::string>{kNice, "-n", "-10", E2E_CAPTURE, "--config",
                               (dir_ / "capture.yaml").string(), "--lcm-url", BusUrl(false),
                               "--rate", std::to_string(options_.rate_hz), "--duration",
                               std::to_string(seconds)},
      On(kCameraHost));
}

std::string LivePipeline::WaitForCapture(double seconds) {
  // It prints one line per camera as it ends.
  const std::string last = rig_.cameras.back().name + ": ";
  const bool ended =
      capture_->WaitForLine(last, milliseconds(static_cast<int64_t>(seconds * 1000) + 60000));
  capture_end_utime_ = NowUtime();
  const int status = capture_->Stop();
  if (!ended) return "the capture service did not end: " + capture_->output();
  if (status != 0) return "the capture service ended with status " + std::to_string(status);
  return {};
}

std::string LivePipeline::RunCapture(double seconds) {
  StartCapture(seconds);
  return WaitForCapture(seconds);
}

void LivePipeline::Drain(milliseconds quiet) {
  size_t count = recorder_->ShapeCount();
  auto last_change = Clock::now();
  const auto end = Clock::now() + milliseconds(30000);
  while (Clock::now() - last_change < quiet && Clock::now() < end) {
    std::this_thread::sleep_for(milliseconds(50));
    if (const size_t now = recorder_->ShapeCount(); now != count) {
      count = now;
      last_change = Clock::now();
    }
  }
  const int64_t after = NowUtime();
  for (const char* service : {"carving", "shape"}) {
    recorder_->WaitForStatus(service, after, milliseconds(5000));
  }
}

std::string LivePipeline::StopAll() {
  std::vector<std::unique_ptr<ChildProcess>*> in_order = {&capture_};
  for (auto& logger : loggers_) in_order.push_back(&logger);
  in_order.insert(in_order.end(), {&shape_, &carving_, &rig_sim_});
  std::string failed;
  for (auto* process : in_order) {
    if (!*process) continue;
    const int status = (*process)->Stop();
    if (status != 0) failed += (failed.empty() ? "" : ", ") + std::to_string(status);
    process->reset();
  }
  loggers_.clear();
  return failed.empty() ? "" : "exit statuses " + failed;
}

Score ScoreShapes(const std::vector<shape_t>& truths, const std::vector<Received<shape_t>>& shapes,
                  int64_t end_utime, int64_t tolerance_us) {
  std::map<int64_t, const shape_t*> by_time;
  for (const shape_t& truth : truths) by_time[truth.trigger_utime] = &truth;
  Score score;
  std::map<int64_t, bool> measured;
  for (const auto& received : shapes) {
    const shape_t& shape = received.message;
    ++score.shapes;
    ScoredShape scored{shape, std::nullopt, 0.0};
    if (shape.valid) {
      ++score.valid;
      const auto it = by_time.lower_bound(shape.trigger_utime);
      if (it != by_time.end() && it->first - shape.trigger_utime <= tolerance_us) {
        scored.truth = *it->second;
        scored.centerline_rms_mm =
            RmsDistanceToPolyline(ToPolyline(shape.centerline), ToPolyline(it->second->centerline));
        measured[it->first] = true;
        ++score.matched;
        score.rms_mean += scored.centerline_rms_mm;
        score.rms_max = std::max(score.rms_max, scored.centerline_rms_mm);
      }
    }
    score.scored.push_back(scored);
  }
  if (score.matched > 0) score.rms_mean /= score.matched;
  for (const auto& [time, truth] : by_time) {
    if (time > end_utime) continue;
    ++score.truths;
    if (!measured.contains(time)) {
      ++score.unmeasured;
      score.unmeasured_times.push_back(time);
    }
  }
  return score;
}

std::string Describe(const Score& score) {
  std::ostringstream out;
  out.precision(3);
  out << std::fixed << score.truths << " frame-sets rendered, " << score.shapes << " shapes ("
      << score.valid << " valid, " << score.matched << " paired with their truth), "
      << score.unmeasured << " rendered sets unmeasured; centreline RMS " << score.rms_mean
      << " mm mean, " << score.rms_max << " mm max";
  return out.str();
}

std::string Describe(const service_status_t& status) {
  std::ostringstream out;
  out << status.service << ": received " << status.received << ", published " << status.published
      << ", dropped " << status.dropped << ", rejected " << status.rejected << ", errors "
      << status.errors << (status.last_error.empty() ? "" : " (last: " + status.last_error + ")");
  return out.str();
}

std::string BadShapes(const Score& score, double rms_mm) {
  std::ostringstream out;
  for (const ScoredShape& s : score.scored) {
    if (s.truth && s.centerline_rms_mm <= rms_mm) continue;
    out << "  frame-set " << s.shape.trigger_seq << " (trigger " << s.shape.trigger_utime
        << " us): ";
    if (!s.shape.valid) {
      out << "invalid: " << s.shape.error << "\n";
    } else if (!s.truth) {
      out << "no truth\n";
    } else {
      out << "centreline RMS " << s.centerline_rms_mm << " mm against the rig's set "
          << s.truth->trigger_seq << " (" << s.truth->trigger_utime - s.shape.trigger_utime
          << " us later)\n";
    }
  }
  return out.str();
}

std::string Report(const Score& score, const Recorder& recorder) {
  std::string out = Describe(score) + "\n";
  for (const char* service : {"rig_sim", "capture", "carving", "shape"}) {
    if (const auto status = recorder.LastStatus(service)) out += Describe(*status) + "\n";
  }
  return out;
}

CaptureDrops ParseCaptureDrops(const std::string& last_error) {
  const auto sum = [&](const std::string& what) {
    int64_t total = 0;
    const std::regex count("(\\d+) " + what);
    for (auto it = std::sregex_iterator(last_error.begin(), last_error.end(), count);
         it != std::sregex_iterator(); ++it) {
      total += std::stoll((*it)[1]);
    }
    return total;
  };
  return {sum("incomplete images"), sum("triggers answered with no image"),
          sum("triggers not sent")};
}

// The rig's truth is at its reference camera's exposure, which the capture
// service keeps within 10 ms after its frame-set's time
// (max_exposure_delay_us): a shape carrying another trigger's time, a period
// off, finds no truth.
int64_t PairingToleranceUs(double rate_hz) {
  return std::min<int64_t>(12'000, static_cast<int64_t>(0.8e6 / rate_hz));
}

}  // namespace shapesense::e2e
