// The capture service end to end, in process over memq://: frame-sets of
// several cameras share their trigger sequence, images are exact, a camera
// that fails to open or is lost is retried while the others keep running,
// and bad options open nothing.
#include "services/capture/capture_service.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <exception>
#include <filesystem>
#include <mutex>
#include <thread>

#include "libs/camera/rig_yaml.h"
#include "libs/core/error.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "services/capture/image_message.h"
#include "services/capture/replay_camera.h"
#include "shapesense/service_status_t.hpp"
#include "shapesense/shape_t.hpp"
#include "tests/services/capture/capture_test_util.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::ReplayConfig;
using testing::SameImage;
using testing::TempDir;

// What the test's subscriber saw.
struct Received {
  std::map<std::string, std::vector<image_t>> images;  // by camera
  std::vector<shape_t> truths;
  std::vector<service_status_t> statuses;
  std::vector<std::string> log;
  std::mutex log_mutex;
};

// Runs the service on a memq:// bus until it ends (its duration) or `until`
// says so, handling its messages on this thread; `during` runs between
// messages.
CaptureSummary RunAndCollect(CaptureServiceArgs args, Received* received,
                             const std::function<bool()>& until = {},
                             const std::function<void()>& during = {}) {
  LcmBus bus("memq://");
  bus.Subscribe<image_t>(channels::kImagePattern,
                         [&](const image_t& m, const std::string&, int64_t) {
                           received->images[m.camera].push_back(m);
                         });
  bus.Subscribe<shape_t>(channels::kTruth, [&](const shape_t& m, const std::string&, int64_t) {
    received->truths.push_back(m);
  });
  bus.Subscribe<service_status_t>(channels::Status("capture"),
                                  [&](const service_status_t& m, const std::string&, int64_t) {
                                    received->statuses.push_back(m);
                                  });
  args.log = [received](const std::string& line) {
    std::lock_guard lock(received->log_mutex);
    received->log.push_back(line);
  };
  std::atomic<bool> stop{false}, done{false};
  CaptureSummary summary;
  std::exception_ptr error;
  std::thread service([&] {
    try {
      summary = RunCaptureService(args, stop, bus);
    } catch (...) {
      error = std::current_exception();
    }
    done = true;
  });
  while (!done) {
    bus.Handle(20);
    if (during) during();
    if (until && until()) stop = true;
  }
  service.join();
  while (bus.Handle(0) > 0) {
  }
  if (error) std::rethrow_exception(error);
  return summary;
}

std::string WriteRig(const fs::path& dir, const Rig& rig) {
  const fs::path path = dir / "rig.yaml";
  WriteFileAtomically(path, FormatRigYaml(rig));
  return path.string();
}

CameraConfig Simulated(const std::string& name) {
  CameraConfig config;
  config.name = name;
  config.backend = "simulated";
  return config;
}

std::vector<int64_t> TriggerSeqs(const std::vector<image_t>& images) {
  std::vector<int64_t> seqs;
  for (const image_t& image : images) seqs.push_back(image.trigger_seq);
  return seqs;
}

bool LogHas(Received& received, const std::string& text) {
  std::lock_guard lock(received.log_mutex);
  return std::any_of(received.log.begin(), received.log.end(),
                     [&](const std::string& line) { return line.find(text) != std::string::npos; });
}

TEST(CaptureServiceTest, SimulatedCamerasPublishFrameSetsWithOneTriggerSequence) {
  TempDir dir("capture_sim");
  const Rig rig = testing::SmallRig(3);
  CaptureServiceArgs args;
  args.options.rig = WriteRig(dir.path(), rig);
  args.options.cameras = {Simulated("cam0"), Simulated("cam1"), Simulated("cam2")};
  args.options.trigger_rate_hz = 15.0;
  args.duration_s = 1.5;
  Received received;
  const CaptureSummary summary = RunAndCollect(args, &received);

  ASSERT_EQ(received.images.size(), 3u);
  size_t shortest = SIZE_MAX;
  for (const auto& [name, images] : received.images) {
    ASSERT_GE(images.size(), 5u) << name;
    shortest = std::min(shortest, images.size());
    const Camera& camera = *rig.Find(name);
    for (size_t i = 0; i < images.size(); ++i) {
      const image_t& image = images[i];
      EXPECT_EQ(image.header.seq, static_cast<int64_t>(i)) << name;
      EXPECT_EQ(image.trigger_seq, static_cast<int64_t>(i)) << name << ": consecutive from 0";
      EXPECT_EQ(image.width, camera.width);
      EXPECT_EQ(image.height, camera.height);
      EXPECT_EQ(image.pixel_format, static_cast<int>(image_t::PIXEL_BGR8));
      EXPECT_EQ(image.compression, static_cast<int>(image_t::COMPRESSION_NONE));
      EXPECT_EQ(image.row_stride, camera.width * 3);
      EXPECT_EQ(image.size, camera.width * camera.height * 3);
      ASSERT_EQ(image.num_stage_times, 1);
      EXPECT_EQ(image.stage_times[0].stage, "capture");
      EXPECT_EQ(image.stage_times[0].duration_us, image.host_utime - image.trigger_utime);
      EXPECT_GE(image.stage_times[0].duration_us, 0);
      EXPECT_FALSE(testing::DecodedImage(image).empty());
    }
    EXPECT_EQ(summary.cameras.at(name).published, static_cast<int64_t>(images.size()));
    EXPECT_EQ(summary.cameras.at(name).outages, 0);
  }
  // One frame-set: the same trigger time on every camera, and its ground truth.
  for (size_t i = 0; i < shortest; ++i) {
    const int64_t utime = received.images["cam0"][i].trigger_utime;
    EXPECT_EQ(received.images["cam1"][i].trigger_utime, utime);
    EXPECT_EQ(received.images["cam2"][i].trigger_utime, utime);
    ASSERT_LT(i, received.truths.size());
    EXPECT_EQ(received.truths[i].trigger_seq, static_cast<int64_t>(i));
    EXPECT_EQ(received.truths[i].trigger_utime, utime);
    EXPECT_TRUE(received.truths[i].valid);
    EXPECT_NEAR(received.truths[i].length, 160.0, 0.01) << "the default trajectory's length";
  }
  ASSERT_FALSE(received.statuses.empty());
  EXPECT_EQ(received.statuses.front().service, "capture");
  EXPECT_EQ(received.statuses.back().errors, 0);
}

TEST(CaptureServiceTest, ReplayedImagesArrivePixelExactAsPng) {
  TempDir dir("capture_replay");
  const auto frames = testing::WriteRandomDataset(dir.path(), testing::SmallRig(2), 4);
  CaptureServiceArgs args;
  args.options.cameras = {ReplayConfig("cam0", dir.path().string()),
                          ReplayConfig("cam1", dir.path().string())};
  args.options.compression = "png";
  args.options.trigger_rate_hz = 20.0;
  args.duration_s = 0.8;
  Received received;
  RunAndCollect(args, &received);
  for (int camera = 0; camera < 2; ++camera) {
    const std::vector<image_t>& images = received.images["cam" + std::to_string(camera)];
    ASSERT_GE(images.size(), 5u) << "more than the dataset: it loops";
    for (const image_t& image : images) {
      EXPECT_EQ(image.compression, static_cast<int>(image_t::COMPRESSION_PNG));
      EXPECT_EQ(image.row_stride, 0);
      EXPECT_TRUE(SameImage(testing::DecodedImage(image), frames[image.trigger_seq % 4][camera]))
          << "cam" << camera << " seq " << image.trigger_seq;
    }
  }
}

TEST(CaptureServiceTest, ACameraThatFailsToOpenIsRetriedWhileTheOthersRun) {
  TempDir dir("capture_retry");
  const fs::path good = dir.path() / "good";
  const fs::path late = dir.path() / "late";
  const auto frames = testing::WriteRandomDataset(good, testing::SmallRig(1), 3);
  CaptureServiceArgs args;
  args.options.cameras = {ReplayConfig("cam0", good.string()), ReplayConfig("cam1", late.string())};
  args.options.trigger_rate_hz = 20.0;
  args.options.reconnect_interval_s = 0.1;
  Received received;
  bool created = false;
  // Once cam0 has run a while, cam1's dataset appears (whole, by a rename).
  const auto create_late = [&] {
    if (created || received.images["cam0"].size() < 10) return;
    const fs::path staging = dir.path() / "staging";
    const Rig rig = testing::SmallRig(2);
    testing::WriteRandomDataset(staging, rig, 3, 9);
    fs::rename(staging, late);
    created = true;
  };
  const auto cam1_back = [&] {
    return received.images["cam1"].size() >= 5 && received.statuses.size() >= 2;
  };
  const CaptureSummary summary = RunAndCollect(args, &received, cam1_back, create_late);

  EXPECT_EQ(summary.cameras.at("cam0").outages, 0);
  EXPECT_EQ(summary.cameras.at("cam1").outages, 1);
  const std::vector<int64_t> cam0 = TriggerSeqs(received.images["cam0"]);
  for (size_t i = 0; i < cam0.size(); ++i)
    ASSERT_EQ(cam0[i], static_cast<int64_t>(i)) << "cam0 never stopped";
  for (const image_t& image : received.images["cam0"]) {
    EXPECT_TRUE(SameImage(testing::DecodedImage(image), frames[image.trigger_seq % 3][0]));
  }
  const std::vector<int64_t> cam1 = TriggerSeqs(received.images["cam1"]);
  ASSERT_GE(cam1.size(), 5u);
  EXPECT_GE(cam1.front(), 10) << "cam1 joined late, in step with the frame-sets";
  const bool reported =
      std::any_of(received.statuses.begin(), received.statuses.end(), [](const auto& s) {
        return s.errors >= 1 && s.last_error.find("cam1: ") == 0 && s.dropped > 0;
      });
  EXPECT_TRUE(reported) << "the status names cam1 and counts its missed frame-sets";
  EXPECT_TRUE(LogHas(received, "cam1: "));
  EXPECT_TRUE(LogHas(received, "cam1: reopened after"));
  EXPECT_TRUE(LogHas(received, "cam1: images again, " + std::to_string(cam1.front()) +
                                   " frame-sets missed (0-" + std::to_string(cam1.front() - 1) +
                                   ")"));
}

// A replay camera that is lost once, after a few frames.
class FlakyCamera : public ReplayCamera {
 public:
  using ReplayCamera::ReplayCamera;
  bool Grab(std::chrono::milliseconds timeout, CameraFrame* frame) override {
    if (++grabs_ == 4) throw CameraError(name() + ": lost (unplugged by the test)");
    return ReplayCamera::Grab(timeout, frame);
  }

 private:
  int grabs_ = 0;
};

TEST(CaptureServiceTest, ALostCameraIsReopened) {
  TempDir dir("capture_lost");
  testing::WriteRandomDataset(dir.path(), testing::SmallRig(2), 3);
  CaptureServiceArgs args;
  args.options.cameras = {ReplayConfig("cam0", dir.path().string()),
                          ReplayConfig("cam1", dir.path().string())};
  args.options.trigger_rate_hz = 20.0;
  args.options.reconnect_interval_s = 0.1;
  args.make_backend = [](const CameraConfig& config,
                         const BackendContext& context) -> std::unique_ptr<CameraBackend> {
    if (config.name == "cam1") return std::make_unique<FlakyCamera>(config);
    return MakeCameraBackend(config, context);
  };
  Received received;
  const auto enough = [&] {
    return received.images["cam1"].size() >= 8 && received.statuses.size() >= 2;
  };
  const CaptureSummary summary = RunAndCollect(args, &received, enough);
  EXPECT_EQ(summary.cameras.at("cam1").outages, 1);
  EXPECT_EQ(summary.cameras.at("cam1").stats.reconnects, 1);
  EXPECT_EQ(summary.cameras.at("cam0").outages, 0);
  const std::vector<int64_t> seqs = TriggerSeqs(received.images["cam1"]);
  EXPECT_TRUE(std::is_sorted(seqs.begin(), seqs.end()));
  EXPECT_TRUE(LogHas(received, "cam1: lost (unplugged by the test)"));
  EXPECT_TRUE(LogHas(received, "cam1: images again after "));
  EXPECT_TRUE(std::any_of(received.statuses.begin(), received.statuses.end(),
                          [](const auto& s) { return s.last_error.find("cam1: lost") == 0; }));
}

// A replay camera whose third trigger blocks for a while, as a GigE camera
// that vanished blocks in Aravis until its control channel times out.
class BlockingTriggerCamera : public ReplayCamera {
 public:
  using ReplayCamera::ReplayCamera;
  void Trigger(int64_t seq, int64_t utime) override {
    if (++triggers_ == 3) std::this_thread::sleep_for(std::chrono::milliseconds(1000));
    ReplayCamera::Trigger(seq, utime);
  }

 private:
  int triggers_ = 0;
};

TEST(CaptureServiceTest, ACameraBlockedInItsTriggerHoldsUpNoOther) {
  TempDir dir("capture_blocked");
  testing::WriteRandomDataset(dir.path(), testing::SmallRig(2), 3);
  CaptureServiceArgs args;
  args.options.cameras = {ReplayConfig("cam0", dir.path().string()),
                          ReplayConfig("cam1", dir.path().string())};
  args.options.trigger_rate_hz = 20.0;
  args.make_backend = [](const CameraConfig& config,
                         const BackendContext& context) -> std::unique_ptr<CameraBackend> {
    if (config.name == "cam1") return std::make_unique<BlockingTriggerCamera>(config);
    return MakeCameraBackend(config, context);
  };
  Received received;
  const auto enough = [&] { return received.images["cam0"].size() >= 45; };
  const CaptureSummary summary = RunAndCollect(args, &received, enough);
  const std::vector<int64_t> cam0 = TriggerSeqs(received.images["cam0"]);
  for (size_t i = 0; i < cam0.size(); ++i) ASSERT_EQ(cam0[i], static_cast<int64_t>(i));
  EXPECT_GT(summary.cameras.at("cam1").missed_triggers, 0) << "stale triggers were skipped";
  EXPECT_EQ(summary.cameras.at("cam0").missed_triggers, 0);
  const std::vector<int64_t> cam1 = TriggerSeqs(received.images["cam1"]);
  ASSERT_FALSE(cam1.empty());
  EXPECT_TRUE(std::is_sorted(cam1.begin(), cam1.end()));
  EXPECT_GT(cam1.back(), 30) << "cam1 went on after its blocked trigger";
}

TEST(CaptureServiceTest, BadOptionsOpenNoCamera) {
  int made = 0;
  CaptureServiceArgs args;
  args.make_backend = [&](const CameraConfig& config, const BackendContext& context) {
    ++made;
    return MakeCameraBackend(config, context);
  };
  std::atomic<bool> stop{false};
  args.options.cameras = {Simulated("cam0"), Simulated("cam0")};
  EXPECT_THAT([&] { RunCaptureService(args, stop); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("cameras[1].name")));
  args.options.cameras = {ReplayConfig("cam1", "/data"), Simulated("cam0")};
  args.options.rig = "/nonexistent/rig.yaml";
  args.lcm_url = "memq://";
  EXPECT_THAT([&] { RunCaptureService(args, stop); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("/nonexistent/rig.yaml")));
  args.options.rig = "";
  args.options.simulation.trajectory_file = "/nonexistent/trajectory.yaml";
  EXPECT_THAT([&] { RunCaptureService(args, stop); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("/nonexistent/trajectory.yaml")));
  EXPECT_EQ(made, 0);
}

TEST(CaptureServiceTest, TheSimulationTakesTheRigSimulatorsTrajectoryFile) {
  TempDir dir("capture_trajectory");
  WriteFileAtomically(dir.path() / "trajectory.yaml",
                      "keyframes: [{time: 0, shape: arc, length: 120, bend_angle: 1.0}]\n"
                      "loop_period: 3\n");
  CaptureServiceOptions options;
  options.cameras = {Simulated("cam0")};
  options.simulation.trajectory_file = (dir.path() / "trajectory.yaml").string();
  const auto world = MakeSimulatedWorld(options, 0);
  ASSERT_NE(world, nullptr);
  EXPECT_EQ(world->options().trajectory.loop_period, 3.0);
  EXPECT_NEAR(TruthOf(world->SceneAtUtime(1'000'000)).length, 120.0, 0.01);
  options.cameras = {ReplayConfig("cam0", "/data")};
  EXPECT_EQ(MakeSimulatedWorld(options, 0), nullptr) << "no simulated camera, no world";
}

TEST(CaptureServiceTest, AFreeRunningCameraPublishesWithoutTriggerSequence) {
  TempDir dir("capture_free");
  testing::WriteRandomDataset(dir.path(), testing::SmallRig(1), 2);
  CaptureServiceArgs args;
  CameraConfig free_run = ReplayConfig("cam0", dir.path().string(), "free_run");
  free_run.frame_rate = 40.0;
  free_run.pixel_format = "Mono8";
  args.options.cameras = {free_run};
  Received received;
  RunAndCollect(args, &received, [&] { return received.images["cam0"].size() >= 4; });
  for (const image_t& image : received.images["cam0"]) {
    EXPECT_EQ(image.trigger_seq, -1);
    EXPECT_EQ(image.pixel_format, static_cast<int>(image_t::PIXEL_MONO8));
    EXPECT_EQ(image.row_stride, image.width);
  }
  EXPECT_TRUE(received.truths.empty()) << "no simulated camera, no truth";
}

}  // namespace
}  // namespace shapesense
