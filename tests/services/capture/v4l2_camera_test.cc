// The V4L2 backend against a fake driver: negotiation, every pixel format,
// buffer timestamps, buffer recycling, EAGAIN, corrupt and error buffers, a
// device that vanishes and comes back, and the latched software trigger.
#include "services/capture/v4l2_camera.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "runtime/lcm/lcm_bus.h"
#include "tests/services/capture/fake_v4l2_device.h"

namespace shapesense {
namespace {

using testing::FakeV4l2Driver;
using testing::FakeV4l2Options;
using ::testing::HasSubstr;
constexpr auto kWait = std::chrono::milliseconds(50);

CameraConfig V4l2Config(const std::string& format, const std::string& trigger = "free_run") {
  CameraConfig config;
  config.name = "cam1";
  config.backend = "v4l2";
  config.device = "/dev/video7";
  config.pixel_format = format;
  config.width = 64;
  config.height = 48;
  config.trigger = trigger;
  config.buffer_count = 4;
  return config;
}

struct Harness {
  std::shared_ptr<FakeV4l2Driver> driver;
  std::unique_ptr<V4l2Camera> camera;
};

Harness MakeCamera(const CameraConfig& config, FakeV4l2Options options = {}) {
  auto driver = std::make_shared<FakeV4l2Driver>(std::move(options));
  return {driver, std::make_unique<V4l2Camera>(config, driver->MakeDevice())};
}

cv::Mat RandomBgr(int width, int height, uint32_t seed) {
  cv::Mat image(height, width, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

// A smooth image (JPEG keeps it within a few grey levels).
cv::Mat SmoothBgr(int width, int height, uint32_t seed) {
  cv::Mat image = RandomBgr(width / 8, height / 8, seed);
  cv::resize(image, image, cv::Size(width, height), 0, 0, cv::INTER_CUBIC);
  return image;
}

// Rows of `image` (already in the wire's channel order) with `padding` bytes after each.
std::vector<uint8_t> Rows(const cv::Mat& image, int padding) {
  std::vector<uint8_t> bytes;
  for (int y = 0; y < image.rows; ++y) {
    bytes.insert(bytes.end(), image.ptr(y), image.ptr(y) + image.cols * image.elemSize());
    bytes.insert(bytes.end(), static_cast<size_t>(padding), uint8_t{0x5a});
  }
  return bytes;
}

// BT.601 video-range YCbCr to BGR, written out independently of OpenCV.
cv::Vec3b YuvToBgr(int y, int u, int v) {
  const double c = 1.164 * (y - 16);
  auto clamp = [](double x) { return cv::saturate_cast<uint8_t>(x); };
  return {clamp(c + 2.018 * (u - 128)), clamp(c - 0.813 * (v - 128) - 0.391 * (u - 128)),
          clamp(c + 1.596 * (v - 128))};
}

// Largest difference of any pixel and channel; infinite when the images differ in size or type.
double MaxDifference(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return std::numeric_limits<double>::infinity();
  return cv::norm(a, b, cv::NORM_INF);
}

CameraFrame GrabOne(V4l2Camera& camera) {
  CameraFrame frame;
  EXPECT_TRUE(camera.Grab(kWait, &frame));
  return frame;
}

TEST(V4l2CameraTest, OpenNegotiatesFormatRateExposureAndBuffers) {
  CameraConfig config = V4l2Config("MJPG");
  config.buffer_count = 8;
  config.frame_rate = 25.0;
  config.exposure_us = 8000.0;
  Harness rig = MakeCamera(config);
  rig.camera->Open();
  EXPECT_TRUE(rig.camera->IsOpen());
  EXPECT_EQ(rig.driver->pixel_format(), V4L2_PIX_FMT_MJPEG);
  EXPECT_EQ(rig.driver->buffer_count(), 4u) << "the driver's limit, not the request";
  EXPECT_EQ(rig.driver->mapped(), 4);
  EXPECT_EQ(rig.driver->queued_buffers(), 4u);
  EXPECT_TRUE(rig.driver->streaming());
  const v4l2_fract period = rig.driver->time_per_frame();
  EXPECT_DOUBLE_EQ(static_cast<double>(period.denominator) / period.numerator, 25.0);
  EXPECT_EQ(rig.driver->controls().at(V4L2_CID_EXPOSURE_AUTO), V4L2_EXPOSURE_MANUAL);
  EXPECT_EQ(rig.driver->controls().at(V4L2_CID_EXPOSURE_ABSOLUTE), 80);  // units of 100 µs
  rig.camera->Close();
  EXPECT_FALSE(rig.driver->is_open());
  EXPECT_EQ(rig.driver->mapped(), 0);
  EXPECT_EQ(rig.driver->buffer_count(), 0u);
}

TEST(V4l2CameraTest, DriversWithoutRateOrExposureControlsStillStream) {
  FakeV4l2Options options;
  options.time_per_frame = false;
  options.exposure_controls = false;
  Harness rig = MakeCamera(V4l2Config("BGR3"), options);
  rig.camera->Open();
  const cv::Mat image = RandomBgr(64, 48, 1);
  rig.driver->AddFrame(Rows(image, 0), 1000);
  const CameraFrame frame = GrabOne(*rig.camera);
  EXPECT_EQ(MaxDifference(frame.image, image), 0.0);
  EXPECT_EQ(frame.exposure_us, 0.0) << "exposure unknown when the driver has no control for it";
}

class RawFormatTest : public ::testing::TestWithParam<std::tuple<std::string, int>> {};

TEST_P(RawFormatTest, RgbAndBgrRowsArriveExactlyAsBgr) {
  const auto [format, padding] = GetParam();
  FakeV4l2Options options;
  options.row_padding = padding;
  Harness rig = MakeCamera(V4l2Config(format), options);
  rig.camera->Open();
  for (uint32_t seed = 0; seed < 3; ++seed) {
    const cv::Mat bgr = RandomBgr(64, 48, seed);
    cv::Mat wire = bgr.clone();
    if (format == "RGB3") cv::cvtColor(bgr, wire, cv::COLOR_BGR2RGB);
    rig.driver->AddFrame(Rows(wire, padding), 1000 + seed);
    const CameraFrame frame = GrabOne(*rig.camera);
    ASSERT_EQ(frame.image.type(), CV_8UC3);
    ASSERT_EQ(frame.image.size(), bgr.size());
    EXPECT_EQ(MaxDifference(frame.image, bgr), 0.0) << format << " padding " << padding;
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, RawFormatTest,
                         ::testing::Combine(::testing::Values("RGB3", "BGR3"),
                                            ::testing::Values(0, 8)));

TEST(V4l2CameraTest, YuyvConvertsWithBt601) {
  for (const int padding : {0, 16}) {
    FakeV4l2Options options;
    options.row_padding = padding;
    Harness rig = MakeCamera(V4l2Config("YUYV"), options);
    rig.camera->Open();
    cv::Mat yuyv(48, 64, CV_8UC2);
    cv::RNG rng(7);
    rng.fill(yuyv, cv::RNG::UNIFORM, 16, 236);  // video range
    rig.driver->AddFrame(Rows(yuyv, padding), 5);
    const CameraFrame frame = GrabOne(*rig.camera);
    ASSERT_EQ(frame.image.size(), cv::Size(64, 48));
    for (int y = 0; y < 48; ++y) {
      for (int x = 0; x < 64; ++x) {
        const cv::Vec2b* row = yuyv.ptr<cv::Vec2b>(y);
        const int pair = x & ~1;  // Y0 U Y1 V: the pair shares U and V
        const cv::Vec3b want = YuvToBgr(row[x][0], row[pair][1], row[pair + 1][1]);
        const cv::Vec3b got = frame.image.at<cv::Vec3b>(y, x);
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(got[c], want[c], 2) << "pixel " << x << "," << y;
      }
    }
  }
}

TEST(V4l2CameraTest, MjpegFramesDecodeAndCorruptOnesAreDroppedAndCounted) {
  Harness rig = MakeCamera(V4l2Config("MJPEG"));
  rig.camera->Open();
  const cv::Mat first = SmoothBgr(64, 48, 1);
  const cv::Mat second = SmoothBgr(64, 48, 2);
  std::vector<uint8_t> jpeg_first, jpeg_second, other_size;
  cv::imencode(".jpg", first, jpeg_first, {cv::IMWRITE_JPEG_QUALITY, 95});
  cv::imencode(".jpg", second, jpeg_second, {cv::IMWRITE_JPEG_QUALITY, 95});
  cv::imencode(".jpg", SmoothBgr(32, 24, 3), other_size);
  std::vector<uint8_t> truncated(jpeg_first.begin(), jpeg_first.begin() + 40);
  std::vector<uint8_t> garbage(3000);
  std::mt19937 random(5);
  for (uint8_t& byte : garbage) byte = static_cast<uint8_t>(random());
  rig.driver->AddFrame(jpeg_first, 10);
  for (auto& bad : {truncated, garbage, other_size}) rig.driver->AddFrame(bad, 20);
  rig.driver->AddFrame(jpeg_second, 30);

  const CameraFrame a = GrabOne(*rig.camera);
  const CameraFrame b = GrabOne(*rig.camera);
  EXPECT_EQ(MaxDifference(a.image, cv::imdecode(jpeg_first, cv::IMREAD_COLOR)), 0.0);
  EXPECT_EQ(MaxDifference(b.image, cv::imdecode(jpeg_second, cv::IMREAD_COLOR)), 0.0);
  EXPECT_LT(cv::norm(a.image, first, cv::NORM_L1) / first.total() / 3, 3.0);
  EXPECT_EQ(a.frame_id + 4, b.frame_id) << "three bad frames came between";
  EXPECT_EQ(rig.camera->Stats().incomplete, 3);
  EXPECT_EQ(rig.camera->Stats().frames, 2);
}

TEST(V4l2CameraTest, ErrorFlaggedAndShortBuffersAreNeverDelivered) {
  Harness rig = MakeCamera(V4l2Config("BGR3"));
  rig.camera->Open();
  const cv::Mat good = RandomBgr(64, 48, 3);
  std::vector<uint8_t> bytes = Rows(good, 0);
  rig.driver->AddFrame(bytes, 1, V4L2_BUF_FLAG_ERROR);
  rig.driver->AddFrame(std::vector<uint8_t>(bytes.begin(), bytes.end() - 1), 2);
  rig.driver->AddFrame(bytes, 3);
  const CameraFrame frame = GrabOne(*rig.camera);
  EXPECT_EQ(frame.frame_id, 2);
  EXPECT_EQ(MaxDifference(frame.image, good), 0.0);
  EXPECT_EQ(rig.camera->Stats().incomplete, 2);
}

TEST(V4l2CameraTest, BufferTimestampsArePlacedOnTheEpoch) {
  FakeV4l2Options options;
  Harness rig = MakeCamera(V4l2Config("BGR3"), options);
  rig.camera->Open();
  const std::vector<uint8_t> bytes = Rows(RandomBgr(64, 48, 1), 0);
  std::mt19937_64 random(3);
  for (int i = 0; i < 20; ++i) {
    const int64_t monotonic_us = static_cast<int64_t>(random() % 10'000'000'000ULL);
    rig.driver->AddFrame(bytes, monotonic_us);
    const CameraFrame frame = GrabOne(*rig.camera);
    const int64_t epoch_us = monotonic_us + options.epoch_minus_monotonic_us;
    EXPECT_EQ(frame.device_timestamp_ns, epoch_us * 1000);
    EXPECT_EQ(frame.trigger_utime, epoch_us) << "free run: the frame's own time";
    EXPECT_EQ(frame.trigger_seq, -1);
  }
}

TEST(V4l2CameraTest, BuffersWithoutAMonotonicTimestampTakeTheHostTime) {
  FakeV4l2Options options;
  options.timestamp_clock = V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN;
  Harness rig = MakeCamera(V4l2Config("BGR3"), options);
  rig.camera->Open();
  rig.driver->AddFrame(Rows(RandomBgr(64, 48, 1), 0), 123);
  const int64_t before = NowUtime();
  const CameraFrame frame = GrabOne(*rig.camera);
  EXPECT_EQ(frame.device_timestamp_ns, 0);
  EXPECT_GE(frame.trigger_utime, before);
  EXPECT_LE(frame.trigger_utime, frame.host_utime);
}

TEST(V4l2CameraTest, BuffersGoBackToTheDriver) {
  Harness rig = MakeCamera(V4l2Config("BGR3"));
  rig.camera->Open();
  for (int i = 0; i < 20; ++i) {  // five times the driver's four buffers
    const cv::Mat image = RandomBgr(64, 48, static_cast<uint32_t>(i));
    rig.driver->AddFrame(Rows(image, 0), i);
    const CameraFrame frame = GrabOne(*rig.camera);
    ASSERT_EQ(MaxDifference(frame.image, image), 0.0) << "frame " << i;
    ASSERT_EQ(rig.driver->queued_buffers(), 4u);
  }
  EXPECT_EQ(rig.camera->Stats().frames, 20);
}

TEST(V4l2CameraTest, EagainIsAWaitNotAnError) {
  Harness rig = MakeCamera(V4l2Config("BGR3"));
  rig.camera->Open();
  CameraFrame frame;
  rig.driver->AddSpuriousWakeup();
  EXPECT_FALSE(rig.camera->Grab(kWait, &frame));
  EXPECT_EQ(rig.camera->Stats().timeouts, 1);
  rig.driver->AddSpuriousWakeup();
  rig.driver->AddFrame(Rows(RandomBgr(64, 48, 1), 0), 9);
  EXPECT_TRUE(rig.camera->Grab(kWait, &frame));
  EXPECT_EQ(rig.camera->Stats().incomplete, 0);
}

TEST(V4l2CameraTest, AVanishedDeviceIsACameraErrorAndReopensWhenBack) {
  Harness rig = MakeCamera(V4l2Config("BGR3"));
  rig.camera->Open();
  rig.driver->Unplug();
  CameraFrame frame;
  try {
    rig.camera->Grab(kWait, &frame);
    FAIL() << "expected CameraError";
  } catch (const CameraError& e) {
    EXPECT_THAT(e.what(), HasSubstr("cam1"));
    EXPECT_THAT(e.what(), HasSubstr("/dev/video7"));
  }
  rig.camera->Close();
  EXPECT_FALSE(rig.driver->is_open());
  EXPECT_EQ(rig.driver->mapped(), 0) << "the mappings are released even though the device is gone";
  EXPECT_THROW(rig.camera->Open(), CameraError);
  EXPECT_FALSE(rig.camera->IsOpen());
  rig.driver->Replug();
  rig.camera->Open();
  const cv::Mat image = RandomBgr(64, 48, 4);
  rig.driver->AddFrame(Rows(image, 0), 1);
  EXPECT_EQ(MaxDifference(GrabOne(*rig.camera).image, image), 0.0);
  EXPECT_EQ(rig.camera->Stats().reconnects, 1);
}

TEST(V4l2CameraTest, AFormatOrSizeTheDriverCannotGiveIsAnError) {
  FakeV4l2Options options;
  options.formats = {V4L2_PIX_FMT_YUYV};
  {
    Harness rig = MakeCamera(V4l2Config("MJPG"), options);
    try {
      rig.camera->Open();
      FAIL() << "expected CameraError";
    } catch (const CameraError& e) {
      EXPECT_THAT(e.what(), HasSubstr("cannot deliver 64x48 MJPG"));
      EXPECT_THAT(e.what(), HasSubstr("offers 64x48 YUYV"));
    }
    EXPECT_FALSE(rig.driver->is_open()) << "a failed open leaves nothing open";
  }
  CameraConfig config = V4l2Config("YUYV");
  config.width = 640;
  Harness rig = MakeCamera(config, options);
  EXPECT_THROW(rig.camera->Open(), CameraError);
  EXPECT_FALSE(rig.driver->is_open());
}

TEST(V4l2CameraTest, ADeviceThatCannotStreamIsRejected) {
  FakeV4l2Options options;
  options.capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_READWRITE;
  Harness rig = MakeCamera(V4l2Config("YUYV"), options);
  EXPECT_THROW(rig.camera->Open(), CameraError);
  options.capabilities = V4L2_CAP_VIDEO_OUTPUT | V4L2_CAP_STREAMING;
  rig = MakeCamera(V4l2Config("YUYV"), options);
  EXPECT_THROW(rig.camera->Open(), CameraError);
  EXPECT_FALSE(rig.driver->is_open());
}

TEST(V4l2CameraTest, SoftwareTriggerTakesTheFirstFrameNotOlderThanIt) {
  FakeV4l2Options options;
  Harness rig = MakeCamera(V4l2Config("BGR3", "software"), options);
  rig.camera->Open();
  const int64_t epoch = options.epoch_minus_monotonic_us;
  std::vector<cv::Mat> images;
  for (int i = 0; i < 6; ++i) {
    images.push_back(RandomBgr(64, 48, static_cast<uint32_t>(i)));
    rig.driver->AddFrame(Rows(images.back(), 0), 1000 * (i + 1));  // frames at 1, 2, ... 6 ms
  }
  CameraFrame frame;
  rig.camera->Trigger(7, epoch + 2500);
  ASSERT_TRUE(rig.camera->Grab(kWait, &frame));
  EXPECT_EQ(frame.trigger_seq, 7);
  EXPECT_EQ(frame.trigger_utime, epoch + 2500);
  EXPECT_EQ(MaxDifference(frame.image, images[2]), 0.0) << "the frame stamped 3 ms";
  rig.camera->Trigger(8, epoch + 5000);
  ASSERT_TRUE(rig.camera->Grab(kWait, &frame));
  EXPECT_EQ(frame.trigger_seq, 8);
  EXPECT_EQ(MaxDifference(frame.image, images[4]), 0.0) << "a trigger at a frame's time takes it";
  EXPECT_FALSE(rig.camera->Grab(kWait, &frame))
      << "no trigger pending: the 6 ms frame is not wanted";
  EXPECT_EQ(rig.camera->Stats().incomplete, 0) << "unwanted frames are not faults";
  EXPECT_EQ(rig.camera->Stats().frames, 2);
}

TEST(V4l2CameraTest, ACorruptFrameLeavesTheTriggerForTheNextFrame) {
  FakeV4l2Options options;
  Harness rig = MakeCamera(V4l2Config("MJPG", "software"), options);
  rig.camera->Open();
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", SmoothBgr(64, 48, 1), jpeg);
  rig.driver->AddFrame(std::vector<uint8_t>(jpeg.begin(), jpeg.begin() + 30), 2000);
  rig.driver->AddFrame(jpeg, 3000);
  rig.camera->Trigger(1, options.epoch_minus_monotonic_us + 1000);
  CameraFrame frame;
  ASSERT_TRUE(rig.camera->Grab(kWait, &frame));
  EXPECT_EQ(frame.trigger_seq, 1);
  EXPECT_EQ(frame.device_timestamp_ns, (options.epoch_minus_monotonic_us + 3000) * 1000);
  EXPECT_EQ(rig.camera->Stats().incomplete, 1);
}

TEST(V4l2CameraTest, FourCcNames) {
  for (const std::string name : {"YUYV", "RGB3", "BGR3", "MJPG"}) {
    EXPECT_EQ(FourCcName(V4l2FourCc(name)), name);
  }
  EXPECT_EQ(V4l2FourCc("MJPEG"), V4l2FourCc("MJPG"));
  EXPECT_THROW(V4l2FourCc("NV12"), std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
