// AravisCamera against real GigE Vision cameras (Aravis's fake camera) over
// loopback, inside this test's private network namespace.

#include <arv.h>
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "runtime/process/private_network.h"
#include "services/capture/aravis_camera.h"
#include "tests/services/capture/aravis/fake_gige_camera.h"
#include "tests/support/network_test.h"

namespace shapesense {
namespace {

using nettest::FakeGigeCamera;
using std::chrono::milliseconds;

int64_t Now() { return g_get_real_time(); }

CameraConfig Config(const std::string& device, const std::string& pixel_format = "RGB8") {
  CameraConfig config;
  config.name = "cam_under_test";
  config.device = device;
  config.pixel_format = pixel_format;
  config.width = 64;
  config.height = 48;
  return config;
}

class AravisCameraTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(nettest::PrivateNetworkError(), ""); }

  // A fake camera on 127.0.0.<2 + index>, or a failed test.
  std::unique_ptr<FakeGigeCamera> Serve(int index, const std::string& serial) {
    auto camera = std::make_unique<FakeGigeCamera>(LoopbackAddress(1 + index), serial);
    EXPECT_TRUE(camera->running()) << "the fake camera cannot bind " << LoopbackAddress(1 + index);
    return camera;
  }

  // Opens the camera and spends one warm-up trigger: Aravis's fake camera
  // serves the first trigger after its acquisition started up to 100 ms
  // late (later polls come every millisecond), and that frame, stamped far
  // outside its trigger's window, is dropped (a real camera exposes within
  // microseconds). Every test's frames are therefore the fake's second on.
  static void OpenAndSettle(CameraBackend& camera) {
    camera.Open();
    camera.Trigger(-1, 0);
    CameraFrame warm_up;
    camera.Grab(milliseconds(300), &warm_up);
  }
  static constexpr int64_t kWarmUpFills = 1;

  // Triggers seq and waits for its frame.
  static std::optional<CameraFrame> TriggerAndGrab(CameraBackend& camera, int64_t seq,
                                                   milliseconds timeout = milliseconds(3000)) {
    sent_utime_.push_back(Now());
    camera.Trigger(seq, sent_utime_.back());
    CameraFrame frame;
    if (!camera.Grab(timeout, &frame)) return std::nullopt;
    return frame;
  }

  // The trigger the fake camera answered with frame n: the newest one sent
  // before it made the image.
  static int64_t TriggerOfFill(int64_t fill_utime) {
    int64_t seq = -1;
    for (size_t k = 0; k < sent_utime_.size() && sent_utime_[k] <= fill_utime; ++k) {
      seq = static_cast<int64_t>(k);
    }
    return seq;
  }

  static inline std::vector<int64_t> sent_utime_;
  void TearDown() override { sent_utime_.clear(); }
};

// Each format arrives as the camera sent it: the decoded image equals the
// decoding of the bytes the camera filled.
TEST_F(AravisCameraTest, EveryPixelFormatDecodesToWhatTheCameraSent) {
  const auto fake = Serve(0, "FMT0");
  int64_t frames_before = 0;
  for (const std::string format :
       {"RGB8", "Mono8", "BayerRG8", "BayerGR8", "BayerGB8", "BayerBG8"}) {
    const auto camera = MakeAravisCamera(Config(LoopbackAddress(1), format));
    ASSERT_NO_THROW(OpenAndSettle(*camera)) << format;
    const std::optional<CameraFrame> frame = TriggerAndGrab(*camera, 0);
    ASSERT_TRUE(frame.has_value()) << format;
    const uint32_t code = AravisPixelFormatCode(format);
    const size_t bytes = size_t{64} * 48 * (format == "RGB8" ? 3 : 1);
    frames_before += kWarmUpFills;
    const std::vector<uint8_t> sent = nettest::PatternBytes(frames_before, bytes);
    const cv::Mat expected = DecodeAravisImage(code, sent.data(), sent.size(), 64, 48);
    ASSERT_EQ(frame->image.type(), expected.type()) << format;
    EXPECT_EQ(cv::norm(frame->image, expected, cv::NORM_INF), 0.0) << format;
    EXPECT_EQ(fake->Register(ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT), code) << format;
    ++frames_before;
    camera->Close();
  }
}

TEST_F(AravisCameraTest, AppliesSizeExposureAndTriggerSettings) {
  const auto fake = Serve(0, "CFG0");
  CameraConfig config = Config(LoopbackAddress(1));
  config.width = 320;
  config.height = 200;
  config.exposure_us = 2500.0;
  const auto camera = MakeAravisCamera(config);
  ASSERT_NO_THROW(OpenAndSettle(*camera));
  EXPECT_EQ(fake->Register(ARV_FAKE_CAMERA_REGISTER_WIDTH), 320u);
  EXPECT_EQ(fake->Register(ARV_FAKE_CAMERA_REGISTER_HEIGHT), 200u);
  EXPECT_EQ(fake->Register(ARV_FAKE_CAMERA_REGISTER_EXPOSURE_TIME_US), 2500u);
  EXPECT_EQ(fake->Register(ARV_FAKE_CAMERA_REGISTER_TRIGGER_MODE), 1u);
  EXPECT_EQ(fake->Register(ARV_FAKE_CAMERA_REGISTER_TRIGGER_SOURCE), 1u) << "Software";
  const std::optional<CameraFrame> frame = TriggerAndGrab(*camera, 0);
  ASSERT_TRUE(frame.has_value());
  EXPECT_EQ(frame->image.cols, 320);
  EXPECT_EQ(frame->image.rows, 200);
  EXPECT_DOUBLE_EQ(frame->exposure_us, 2500.0);
}

// One frame per trigger, carrying that trigger's seq and time; nothing else.
TEST_F(AravisCameraTest, SoftwareTriggerGivesExactlyOneFramePerTrigger) {
  const auto fake = Serve(0, "TRG0");
  const auto camera = MakeAravisCamera(Config(LoopbackAddress(1)));
  ASSERT_NO_THROW(OpenAndSettle(*camera));
  for (int64_t seq = 0; seq < 20; ++seq) {
    const std::optional<CameraFrame> frame = TriggerAndGrab(*camera, seq);
    ASSERT_TRUE(frame.has_value())
        << "no frame for trigger " << seq << ": " << camera->Stats().unmatched_reasons;
    EXPECT_EQ(frame->trigger_seq, seq);
    EXPECT_EQ(frame->trigger_utime, sent_utime_.back());
    EXPECT_EQ(nettest::FrameNumberOf(nettest::RawBytesOf(frame->image)), seq + kWarmUpFills);
    EXPECT_GT(frame->device_timestamp_ns, 0);
    EXPECT_GE(frame->host_utime, sent_utime_.back());
  }
  CameraFrame extra;
  EXPECT_FALSE(camera->Grab(milliseconds(300), &extra)) << "a frame nobody triggered";
  EXPECT_EQ(fake->FillTimes().size(), 20u + kWarmUpFills);
  EXPECT_EQ(camera->Stats().frames, 20);
  EXPECT_EQ(camera->Stats().incomplete, 0);
}

// Triggers sent at a steady rate without waiting: each frame still gets the
// trigger the camera answered (the newest one sent before it made the image).
TEST_F(AravisCameraTest, FramesOfATriggerStreamCarryTheirOwnTriggers) {
  const auto fake = Serve(0, "STR0");
  const auto camera = MakeAravisCamera(Config(LoopbackAddress(1)));
  ASSERT_NO_THROW(OpenAndSettle(*camera));
  ASSERT_TRUE(TriggerAndGrab(*camera, 0).has_value());
  std::vector<CameraFrame> frames;
  std::thread grabber([&] {
    CameraFrame frame;
    while (frames.size() < 40 && camera->Grab(milliseconds(2000), &frame)) frames.push_back(frame);
  });
  for (int64_t seq = 1; seq <= 40; ++seq) {
    sent_utime_.push_back(Now());
    camera->Trigger(seq, sent_utime_.back());
    std::this_thread::sleep_for(milliseconds(12));
  }
  grabber.join();
  const std::vector<int64_t> fills = fake->FillTimes();
  ASSERT_GE(frames.size(), 30u);
  for (const CameraFrame& frame : frames) {
    const int64_t n = nettest::FrameNumberOf(nettest::RawBytesOf(frame.image));
    ASSERT_LT(n, static_cast<int64_t>(fills.size()));
    EXPECT_EQ(frame.trigger_seq, TriggerOfFill(fills[n])) << "frame " << n;
  }
}

// 5% of the stream packets dropped: broken images are counted, never
// delivered; every delivered image is byte-exact and on its own trigger.
TEST_F(AravisCameraTest, PacketLossDropsIncompleteFramesAndNeverDeliversABrokenOne) {
  const auto fake = Serve(0, "LOSS0");
  fake->SetPacketLoss(0.05);
  CameraConfig config = Config(LoopbackAddress(1), "Mono8");
  config.width = 640;
  config.height = 480;
  // 21 packets a frame (leader, 19 of data, trailer): 0.95^21, 34% arrive whole.
  config.packet_size = 16384;
  const auto camera = MakeAravisCamera(config);
  ASSERT_NO_THROW(OpenAndSettle(*camera));
  int delivered = 0;
  for (int64_t seq = 0; seq < 40; ++seq) {
    // A broken frame is reported after Aravis's frame retention (100 ms).
    const std::optional<CameraFrame> frame = TriggerAndGrab(*camera, seq, milliseconds(300));
    if (!frame) continue;
    ++delivered;
    const std::vector<uint8_t> raw = nettest::RawBytesOf(frame->image);
    const int64_t n = nettest::FrameNumberOf(raw);
    ASSERT_EQ(raw, nettest::PatternBytes(n, raw.size()))
        << "corrupted image delivered, frame " << n;
    EXPECT_EQ(frame->trigger_seq, n - kWarmUpFills)
        << "one trigger, one image: frame n answers trigger n";
  }
  const CameraStats stats = camera->Stats();
  EXPECT_EQ(stats.frames, delivered);
  EXPECT_GT(stats.incomplete, 5) << "5% packet loss breaks about 66% of 21-packet frames";
  EXPECT_GT(delivered, 3) << "about 34% of 21-packet frames get through 5% loss";
  EXPECT_LE(stats.frames + stats.incomplete, 40 + kWarmUpFills);
}

// The camera disappears: Grab() throws naming camera and device; Open()
// fails while it is away and succeeds once it is back.
TEST_F(AravisCameraTest, ALostCameraRaisesAndReconnectsWhenItReturns) {
  auto fake = Serve(0, "GONE0");
  const CameraConfig config = Config(LoopbackAddress(1));
  const auto camera = MakeAravisCamera(config);
  ASSERT_NO_THROW(OpenAndSettle(*camera));
  ASSERT_TRUE(TriggerAndGrab(*camera, 0).has_value());
  fake.reset();
  std::string error;
  const int64_t give_up = Now() + 20'000'000;
  for (int64_t seq = 1; error.empty() && Now() < give_up; ++seq) {
    try {
      TriggerAndGrab(*camera, seq);
    } catch (const CameraError& e) {
      error = e.what();
    }
  }
  ASSERT_FALSE(error.empty()) << "no CameraError within 20 s of the camera vanishing";
  EXPECT_NE(error.find("cam_under_test"), std::string::npos) << error;
  EXPECT_NE(error.find(config.device), std::string::npos) << error;
  camera->Close();
  EXPECT_THROW(camera->Open(), CameraError) << "nothing to open";
  EXPECT_FALSE(camera->IsOpen());
  fake = Serve(0, "GONE0");
  ASSERT_NO_THROW(OpenAndSettle(*camera));
  const std::optional<CameraFrame> frame = TriggerAndGrab(*camera, 100);
  ASSERT_TRUE(frame.has_value());
  EXPECT_EQ(frame->trigger_seq, 100);
  EXPECT_EQ(camera->Stats().reconnects, 1);
}

TEST_F(AravisCameraTest, OpensBySerialNumberAndByDeviceId) {
  const auto fake = Serve(2, "SER7");
  for (const std::string& device :
       std::vector<std::string>{"SER7", "Aravis-Fake-SER7", LoopbackAddress(3)}) {
    const auto camera = MakeAravisCamera(Config(device));
    ASSERT_NO_THROW(OpenAndSettle(*camera)) << device;
    EXPECT_TRUE(TriggerAndGrab(*camera, 0).has_value()) << device;
  }
}

TEST_F(AravisCameraTest, FailuresNameTheCameraAndTheDevice) {
  const auto fake = Serve(0, "ERR0");
  const std::vector<CameraConfig> bad = [] {
    CameraConfig missing = Config("NO-SUCH-SERIAL");
    CameraConfig line = Config(LoopbackAddress(1));
    line.trigger = "hardware";
    line.trigger_line = "Line7";                               // the fake camera has Line0 only
    CameraConfig format = Config(LoopbackAddress(1), "YUYV");  // not a GenICam name
    return std::vector<CameraConfig>{missing, line, format};
  }();
  for (const CameraConfig& config : bad) {
    const auto camera = MakeAravisCamera(config);
    try {
      camera->Open();
      ADD_FAILURE() << "opened " << config.device << " with a bad setting (" << config.pixel_format
                    << ", trigger line " << config.trigger_line << ")";
    } catch (const CameraError& e) {
      EXPECT_NE(std::string(e.what()).find("cam_under_test"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(config.device), std::string::npos) << e.what();
    }
    EXPECT_FALSE(camera->IsOpen());
  }
}

TEST_F(AravisCameraTest, HardwareTriggerWaitsForTheLine) {
  const auto fake = Serve(0, "HW0");
  CameraConfig config = Config(LoopbackAddress(1));
  config.trigger = "hardware";
  config.trigger_line = "Line0";
  const auto camera = MakeAravisCamera(config);
  ASSERT_NO_THROW(OpenAndSettle(*camera));
  EXPECT_EQ(fake->Register(ARV_FAKE_CAMERA_REGISTER_TRIGGER_MODE), 1u);
  EXPECT_EQ(fake->Register(ARV_FAKE_CAMERA_REGISTER_TRIGGER_SOURCE), 0u) << "Line0";
  camera->Trigger(0, 0);  // announced only: nothing is sent
  CameraFrame frame;
  EXPECT_FALSE(camera->Grab(milliseconds(300), &frame));
  EXPECT_TRUE(fake->FillTimes().empty());
}

TEST_F(AravisCameraTest, FreeRunStreamsAtTheFrameRateWithoutTriggers) {
  const auto fake = Serve(0, "FREE0");
  CameraConfig config = Config(LoopbackAddress(1));
  config.trigger = "free_run";
  config.frame_rate = 50.0;
  const auto camera = MakeAravisCamera(config);
  ASSERT_NO_THROW(OpenAndSettle(*camera));
  EXPECT_EQ(fake->Register(ARV_FAKE_CAMERA_REGISTER_TRIGGER_MODE), 0u);
  EXPECT_EQ(fake->Register(ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US), 20'000u);
  for (int i = 0; i < 5; ++i) {
    CameraFrame frame;
    ASSERT_TRUE(camera->Grab(milliseconds(2000), &frame));
    EXPECT_EQ(frame.trigger_seq, -1);
  }
}

}  // namespace
}  // namespace shapesense
