// The virtual rig over the real GigE Vision protocol, read by the capture
// service's Aravis backend, inside this test's private network namespace:
// in-process (every image checked pixel for pixel against its frame-set's
// rendering) and as the shapesense-rig-sim process (truth on LCM multicast,
// images consistent with it, packet loss, a camera going away and back).

#include <gtest/gtest.h>
#include <lcm/lcm.h>
#include <signal.h>

#include <atomic>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include "libs/camera/rig_yaml.h"
#include "libs/sim/scene_generators.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/process/child_process.h"
#include "runtime/process/private_network.h"
#include "services/capture/aravis_camera.h"
#include "services/rig_sim/fake_camera_server.h"
#include "services/rig_sim/raw_image.h"
#include "tests/support/network_test.h"

namespace shapesense {
namespace {

using std::chrono::milliseconds;

constexpr const char* kLcmUrl = "udpm://239.255.76.67:7667?ttl=0";

CameraConfig CameraAt(int index, const std::string& pixel_format = "RGB8") {
  CameraConfig config;
  config.name = "cam" + std::to_string(index);
  config.device = LoopbackAddress(index);
  config.pixel_format = pixel_format;
  // One trigger at a time here: a generous latency keeps a loaded test
  // machine's late watcher from dropping frames these tests look at.
  config.trigger_latency_us = 50'000;
  config.max_exposure_delay_us = 200'000;
  return config;
}

std::vector<std::unique_ptr<CameraBackend>> OpenCameras(const std::vector<std::string>& formats) {
  std::vector<std::unique_ptr<CameraBackend>> cameras;
  for (size_t i = 0; i < formats.size(); ++i) {
    cameras.push_back(MakeAravisCamera(CameraAt(static_cast<int>(i), formats[i])));
    cameras.back()->Open();
  }
  return cameras;
}

// Triggers every camera for `seq` and grabs each one's frame (empty on timeout).
std::vector<std::optional<CameraFrame>> TriggerSet(
    std::vector<std::unique_ptr<CameraBackend>>& cameras, int64_t seq,
    milliseconds timeout = milliseconds(5000)) {
  const int64_t now = NowUtime();
  for (auto& camera : cameras) camera->Trigger(seq, now);
  std::vector<std::optional<CameraFrame>> frames;
  for (auto& camera : cameras) {
    CameraFrame frame;
    frames.push_back(camera->Grab(timeout, &frame) ? std::optional(frame) : std::nullopt);
  }
  return frames;
}

// What the capture backend makes of the rendering in `format`.
cv::Mat AsDelivered(const cv::Mat& bgr, const std::string& format) {
  const uint32_t code = AravisPixelFormatCode(format);
  std::vector<uint8_t> raw(bgr.total() * static_cast<size_t>(RawBytesPerPixel(code)));
  EncodeRawImage(bgr, code, bgr.cols, bgr.rows, raw.data(), raw.size());
  return DecodeAravisImage(code, raw.data(), raw.size(), bgr.cols, bgr.rows);
}

class RigSimNetworkTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(nettest::PrivateNetworkError(), ""); }
};

// What a PTP-synchronised camera reports: each image is stamped with its
// exposure on the host's clock, after its trigger left and within the
// camera's latency of its acknowledgement, its block id counts exposures,
// and it shows the scene at that instant, pixel for pixel.
TEST_F(RigSimNetworkTest, EveryImageShowsTheSceneAtTheExposureItIsStampedWith) {
  const Rig rig = MakeSyntheticRig(SyntheticRigOptions{});
  FakeCameraServer server(rig, TrajectoryOptions{}, {"127.0.0.1", "127.0.0.2", "127.0.0.3"}, 11,
                          NowUtime());
  for (int i = 0; i < 3; ++i) server.Start(i);
  const std::vector<std::string> formats = {"RGB8", "Mono8", "BayerRG8"};
  auto cameras = OpenCameras(formats);
  std::vector<int64_t> last_exposure(3, 0);
  for (int64_t seq = 0; seq < 6; ++seq) {
    const int64_t before = NowUtime();
    const auto frames = TriggerSet(cameras, seq);
    for (int i = 0; i < 3; ++i) {
      ASSERT_TRUE(frames[i].has_value()) << "camera " << i << " set " << seq;
      EXPECT_EQ(frames[i]->trigger_seq, seq);
      EXPECT_EQ(frames[i]->frame_id, seq + 1) << "block ids count exposures from 1";
      const std::optional<CameraExposure> exposure = server.FindExposure(i, frames[i]->frame_id);
      ASSERT_TRUE(exposure.has_value()) << "camera " << i << " has no exposure " << seq + 1;
      EXPECT_EQ(frames[i]->device_timestamp_ns, exposure->utime * 1000);
      EXPECT_GE(exposure->utime, before);
      EXPECT_GT(exposure->utime, last_exposure[static_cast<size_t>(i)]);
      last_exposure[static_cast<size_t>(i)] = exposure->utime;
      const cv::Mat expected = AsDelivered(server.Render(*exposure), formats[i]);
      ASSERT_EQ(frames[i]->image.type(), expected.type());
      EXPECT_EQ(cv::norm(frames[i]->image, expected, cv::NORM_INF), 0.0)
          << "camera " << i << " (" << formats[i] << ") does not show its exposure " << seq + 1;
    }
  }
  EXPECT_FALSE(server.FindExposure(0, 7).has_value()) << "one exposure per trigger";
  EXPECT_EQ(server.TakeReferenceExposures().size(), 6u) << "camera 0's exposures, for the truth";
  EXPECT_EQ(server.images_served(), 18);
  EXPECT_EQ(server.errors(), 0);
}

// Missed triggers make no image and no exposure: those triggers go
// unanswered, and nothing is taken for them. (The fault acts when the
// watcher sees the trigger first; on a busy machine the camera's own thread
// may serve one before.)
TEST_F(RigSimNetworkTest, MissedTriggersMakeNoExposure) {
  const Rig rig = MakeSyntheticRig(SyntheticRigOptions{});
  FakeCameraServer server(rig, TrajectoryOptions{}, {"127.0.0.1", "127.0.0.2", "127.0.0.3"}, 5,
                          NowUtime());
  server.Start(0);
  auto cameras = OpenCameras({"RGB8"});
  ASSERT_TRUE(TriggerSet(cameras, 0)[0].has_value());
  CameraFaults faults;
  faults.miss_ratio = 0.999;
  server.SetFaults(faults);
  int answered = 0;
  for (int64_t seq = 1; seq <= 10; ++seq) {
    const std::optional<CameraFrame> frame = TriggerSet(cameras, seq, milliseconds(300))[0];
    if (!frame) continue;
    ++answered;
    EXPECT_EQ(frame->trigger_seq, seq) << "an image answers its own trigger";
  }
  EXPECT_LE(answered, 7) << "the fault missed too few triggers";
  EXPECT_EQ(server.images_served(), 1 + answered);
  EXPECT_FALSE(server.FindExposure(0, 2 + answered).has_value());
  EXPECT_EQ(cameras[0]->Stats().unmatched_frames, 0);
}

// A trigger answered with the previous image again (the same block id and
// stamp) never passes for an image of that trigger: Aravis's stream or the
// backend's matcher drops it, and the trigger goes unanswered.
TEST_F(RigSimNetworkTest, AStaleImageReSentNeverAnswersALaterTrigger) {
  const Rig rig = MakeSyntheticRig(SyntheticRigOptions{});
  FakeCameraServer server(rig, TrajectoryOptions{}, {"127.0.0.1", "127.0.0.2", "127.0.0.3"}, 6,
                          NowUtime());
  server.Start(0);
  auto cameras = OpenCameras({"RGB8"});
  CameraFaults faults;
  faults.repeat_ratio = 0.999;
  server.SetFaults(faults);
  ASSERT_TRUE(TriggerSet(cameras, 0)[0].has_value());  // kept for the repeats
  int answered = 0;
  for (int64_t seq = 1; seq <= 8; ++seq) {
    const std::optional<CameraFrame> frame = TriggerSet(cameras, seq, milliseconds(300))[0];
    if (!frame) continue;
    ++answered;
    EXPECT_EQ(frame->trigger_seq, seq) << "an image answers its own trigger";
    EXPECT_NE(frame->frame_id, 1) << "the stale image was taken for a new one";
  }
  EXPECT_LE(answered, 4) << "the fault repeated too few images";
  EXPECT_EQ(server.images_served(), 1 + answered) << "a repeat is no new exposure";
}

// The tube's pixels: much less green than the backdrop.
int TubePixels(const cv::Mat& bgr) {
  cv::Mat green;
  cv::extractChannel(bgr, green, 1);
  return cv::countNonZero(green < 110);
}

TEST_F(RigSimNetworkTest, BackdropOnlyShowsNoManipulator) {
  const Rig rig = MakeSyntheticRig(SyntheticRigOptions{});
  FakeCameraServer server(rig, TrajectoryOptions{}, {"127.0.0.1", "127.0.0.2", "127.0.0.3"}, 3,
                          NowUtime());
  server.Start(0);
  auto cameras = OpenCameras({"RGB8"});
  const auto with_tube = TriggerSet(cameras, 0);
  server.SetBackdropOnly(true);
  const auto backdrop = TriggerSet(cameras, 1);
  ASSERT_TRUE(with_tube[0].has_value() && backdrop[0].has_value());
  EXPECT_GT(TubePixels(with_tube[0]->image), 1000);
  EXPECT_EQ(TubePixels(backdrop[0]->image), 0);
}

// Truth messages received on LCM, by trigger_seq. Through LCM's C API: in
// GCC 12 builds with -fsanitize=vptr, the C++ API's member-function callback
// is miscompiled (a null handler), which would hide what this test checks.
class TruthListener {
 public:
  TruthListener() : lcm_(lcm_create(kLcmUrl)) {
    if (lcm_ != nullptr) lcm_subscribe(lcm_, channels::kTruth, &TruthListener::OnMessage, this);
    thread_ = std::thread([this] {
      while (lcm_ != nullptr && !stop_) lcm_handle_timeout(lcm_, 50);
    });
  }
  ~TruthListener() {
    stop_ = true;
    thread_.join();
    if (lcm_ != nullptr) lcm_destroy(lcm_);
  }
  bool ok() const { return lcm_ != nullptr; }
  std::map<int64_t, shape_t> Truths() {
    std::lock_guard lock(mutex_);
    return truths_;
  }

 private:
  static void OnMessage(const lcm_recv_buf_t* buffer, const char*, void* self) {
    shape_t truth;
    if (truth.decode(buffer->data, 0, static_cast<int>(buffer->data_size)) < 0) return;
    auto* listener = static_cast<TruthListener*>(self);
    std::lock_guard lock(listener->mutex_);
    listener->truths_[truth.trigger_seq] = truth;
  }

  lcm_t* lcm_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::map<int64_t, shape_t> truths_;
  std::thread thread_;
};

// A fast swing, so that consecutive frame-sets look clearly different.
std::string FastTrajectoryFile() {
  std::string path = ::testing::TempDir() + "rig_sim_fast_trajectory.yaml";
  std::ofstream(path) << "keyframes:\n"
                         "  - {time: 0.0, shape: arc, length: 160, bend_angle: 1.5}\n"
                         "  - {time: 0.2, shape: arc, length: 160, bend_angle: -1.5}\n"
                         "loop_period: 0.4\n";
  return path;
}

ChildProcess StartRigSim(const std::vector<std::string>& extra) {
  std::vector<std::string> argv = {RIG_SIM_BINARY,
                                   "--lcm-url",
                                   kLcmUrl,
                                   "--duration",
                                   "60",
                                   "--ips",
                                   "127.0.0.1,127.0.0.2,127.0.0.3",
                                   "--trajectory",
                                   FastTrajectoryFile()};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return ChildProcess(argv);
}

// The fraction of the truth's centreline that falls on the dark tube in an
// image (the backdrop is bright green, the tube and tapes are not).
double FractionOnTube(const shape_t& truth, const Camera& camera, const cv::Mat& image) {
  int on = 0;
  for (const std::vector<double>& p : truth.centerline) {
    const std::optional<Vec2> pixel = camera.Project(Vec3(p[0], p[1], p[2]));
    if (!pixel || !camera.InImage(*pixel)) continue;
    const cv::Vec3b& bgr = image.at<cv::Vec3b>(static_cast<int>(std::lround((*pixel)(1))),
                                               static_cast<int>(std::lround((*pixel)(0))));
    if (bgr[1] < 120) ++on;
  }
  return static_cast<double>(on) / static_cast<double>(truth.centerline.size());
}

TEST_F(RigSimNetworkTest, TheServicePublishesTruthThatItsImagesShow) {
  TruthListener listener;
  ASSERT_TRUE(listener.ok()) << "LCM cannot start on " << kLcmUrl;
  const std::string rig_path = ::testing::TempDir() + "rig_sim_test_rig.yaml";
  auto rig_sim = StartRigSim({"--seed", "4", "--write-rig", rig_path});
  ASSERT_TRUE(rig_sim.WaitForLine("rig-sim: ready", milliseconds(30000))) << rig_sim.output();
  auto cameras = OpenCameras({"RGB8", "RGB8", "RGB8"});
  const Rig rig = ParseRigYaml(ReadTextFile(rig_path), rig_path);
  ASSERT_EQ(rig.cameras.size(), 3u);
  // By the reference camera's (cam0's) frame id, which the truth carries.
  // The truth is the scene at cam0's exposure; another camera's image is
  // held to it when that camera was exposed within a millisecond of cam0
  // (the triggers go out one after the other; on a busy machine, further apart).
  std::map<int64_t, std::vector<cv::Mat>> images;
  std::map<int64_t, std::vector<bool>> simultaneous;
  for (int64_t seq = 0; seq < 8; ++seq) {
    const auto frames = TriggerSet(cameras, seq);
    for (const auto& frame : frames) {
      ASSERT_TRUE(frame.has_value()) << "set " << seq;
      EXPECT_EQ(frame->trigger_seq, seq);
      images[frames[0]->frame_id].push_back(frame->image);
      simultaneous[frames[0]->frame_id].push_back(
          std::llabs(frame->device_timestamp_ns - frames[0]->device_timestamp_ns) <= 1'000'000);
    }
  }
  std::map<int64_t, shape_t> truths;
  for (int wait = 0; wait < 100 && truths.size() < 8; ++wait) {
    std::this_thread::sleep_for(milliseconds(50));
    truths = listener.Truths();
  }
  ASSERT_EQ(truths.size(), 8u) << "one truth message per exposure of the reference camera";
  int told_apart = 0;  // images the previous set's truth does not fit
  for (const auto& [seq, truth] : truths) {
    ASSERT_TRUE(images.contains(seq)) << "truth for an exposure nobody triggered: " << seq;
    EXPECT_TRUE(truth.valid);
    for (size_t i = 0; i < 3; ++i) {
      if (!simultaneous[seq][i]) continue;
      EXPECT_GT(FractionOnTube(truth, rig.cameras[i], images[seq][i]), 0.95)
          << "camera " << i << " does not show the truth of set " << seq;
      if (seq > 1 && FractionOnTube(truths[seq - 1], rig.cameras[i], images[seq][i]) < 0.9) {
        ++told_apart;
      }
    }
  }
  // The swing reverses every 0.2 s, where consecutive sets look alike.
  EXPECT_GE(told_apart, 6) << "of up to 21: the check cannot tell consecutive sets apart";
  cameras.clear();  // while their device still answers (else each waits out GVCP timeouts)
  EXPECT_EQ(rig_sim.Stop(), 0) << "a clean stop on SIGTERM";
}

TEST_F(RigSimNetworkTest, PacketLossBreaksFramesButNeverDeliversABrokenOne) {
  auto rig_sim = StartRigSim({"--packet-loss", "0.05"});
  ASSERT_TRUE(rig_sim.WaitForLine("rig-sim: ready", milliseconds(30000))) << rig_sim.output();
  CameraConfig config = CameraAt(0, "BayerRG8");
  config.packet_size = 16384;  // 21 packets a frame: about a third arrive whole
  auto camera = MakeAravisCamera(config);
  camera->Open();
  const Rig rig = MakeSyntheticRig(SyntheticRigOptions{});
  int delivered = 0;
  for (int64_t seq = 0; seq < 30; ++seq) {
    camera->Trigger(seq, NowUtime());
    CameraFrame frame;
    if (!camera->Grab(milliseconds(400), &frame)) continue;
    ++delivered;
    // A whole Bayer image: the backdrop's green everywhere but on the tube.
    cv::Mat green;
    cv::extractChannel(frame.image, green, 1);
    EXPECT_GT(cv::mean(green)[0], 120.0) << "a frame with missing data was delivered";
  }
  EXPECT_GT(camera->Stats().incomplete, 5);
  EXPECT_GT(delivered, 2);
}

TEST_F(RigSimNetworkTest, ACameraTakenOffTheNetworkComesBack) {
  auto rig_sim = StartRigSim({"--fault-camera", "cam2"});
  ASSERT_TRUE(rig_sim.WaitForLine("rig-sim: ready", milliseconds(30000))) << rig_sim.output();
  auto camera = MakeAravisCamera(CameraAt(2));
  camera->Open();
  CameraFrame frame;
  camera->Trigger(0, NowUtime());
  ASSERT_TRUE(camera->Grab(milliseconds(5000), &frame));
  rig_sim.Signal(SIGUSR1);
  ASSERT_TRUE(rig_sim.WaitForLine("cam2 off the network", milliseconds(5000))) << rig_sim.output();
  bool lost = false;
  for (int64_t seq = 1; seq < 20 && !lost; ++seq) {
    try {
      camera->Trigger(seq, NowUtime());
      camera->Grab(milliseconds(500), &frame);
    } catch (const CameraError& e) {
      lost = true;
      EXPECT_NE(std::string(e.what()).find("cam2"), std::string::npos) << e.what();
    }
  }
  ASSERT_TRUE(lost) << "the capture side never noticed the camera going away";
  camera->Close();
  rig_sim.Signal(SIGUSR2);
  ASSERT_TRUE(rig_sim.WaitForLine("cam2 back on the network", milliseconds(5000)))
      << rig_sim.output();
  ASSERT_NO_THROW(camera->Open());
  camera->Trigger(100, NowUtime());
  ASSERT_TRUE(camera->Grab(milliseconds(5000), &frame));
  EXPECT_EQ(frame.trigger_seq, 100);
}

}  // namespace
}  // namespace shapesense
