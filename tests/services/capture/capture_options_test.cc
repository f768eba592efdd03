// Camera specs, camera and service validation: every bad value is caught
// before anything is opened, and the error names the key and what was expected.
#include "services/capture/capture_options.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>

#include "libs/core/error.h"
#include "runtime/config_file.h"
#include "runtime/file_io.h"
#include "tests/services/capture/capture_test_util.h"

namespace shapesense {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

TEST(ParseCameraSpecTest, ParsesEveryBackend) {
  const CameraConfig aravis = ParseCameraSpec("cam0=aravis:127.0.0.1");
  EXPECT_EQ(aravis.name, "cam0");
  EXPECT_EQ(aravis.backend, "aravis");
  EXPECT_EQ(aravis.device, "127.0.0.1");
  EXPECT_EQ(aravis.pixel_format, "RGB8");
  const CameraConfig v4l2 = ParseCameraSpec("cam1=v4l2:/dev/video0");
  EXPECT_EQ(v4l2.device, "/dev/video0");
  EXPECT_EQ(v4l2.pixel_format, "YUYV") << "the v4l2 default, not aravis's RGB8";
  EXPECT_EQ(ParseCameraSpec("cam2=replay:/data/set").device, "/data/set");
  const CameraConfig simulated = ParseCameraSpec("cam3=simulated:");
  EXPECT_EQ(simulated.backend, "simulated");
  EXPECT_EQ(simulated.device, "");
  EXPECT_EQ(ParseCameraSpec("left_1=replay:C:/clip.avi").device, "C:/clip.avi")
      << "split at the first ':'";
  EXPECT_EQ(ParseCameraSpec("cam0=aravis:").device, "") << "aravis: the first camera found";
}

TEST(ParseCameraSpecTest, BadSpecsSayWhatIsExpected) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"cam0", "expected NAME=BACKEND:DEVICE"},
      {"cam0=aravis", "expected NAME=BACKEND:DEVICE"},
      {"=aravis:1.2.3.4", "name: expected a non-empty name"},
      {"cam 0=aravis:1.2.3.4", "name: expected a non-empty name"},
      {"cam0=gige:1.2.3.4", "backend: expected aravis, v4l2, replay or simulated, got 'gige'"},
      {"cam1=v4l2:", "device: expected a V4L2 device path"},
      {"cam2=replay:", "device: expected a dataset folder or a video file"},
  };
  for (const auto& [spec, expected] : cases) {
    try {
      ParseCameraSpec(spec);
      ADD_FAILURE() << spec << ": expected std::invalid_argument";
    } catch (const std::invalid_argument& e) {
      EXPECT_THAT(e.what(), HasSubstr("--camera '" + spec + "'"));
      EXPECT_THAT(e.what(), HasSubstr(expected)) << spec;
    }
  }
}

CameraConfig Good(const std::string& backend) {
  CameraConfig config;
  config.name = "cam0";
  config.backend = backend;
  config.device = backend == "v4l2" ? "/dev/video0" : backend == "replay" ? "/data" : "";
  config.pixel_format = DefaultPixelFormat(backend);
  return config;
}

TEST(CameraConfigTest, EveryBadValueNamesItsKey) {
  const std::vector<std::pair<std::function<void(CameraConfig&)>, std::string>> cases = {
      {[](CameraConfig& c) { c.name = "cam/0"; }, "name: "},
      {[](CameraConfig& c) { c.backend = "usb"; }, "backend: "},
      {[](CameraConfig& c) { c.pixel_format = "YUYV"; }, "pixel_format: expected for aravis Mono8"},
      {[](CameraConfig& c) { c.width = 0; }, "width: expected 1-16384 px, got 0"},
      {[](CameraConfig& c) { c.height = 20000; }, "height: "},
      {[](CameraConfig& c) { c.exposure_us = 0.0; }, "exposure_us: "},
      {[](CameraConfig& c) { c.gain_db = -1.0; }, "gain_db: "},
      {[](CameraConfig& c) { c.frame_rate = 0.0; }, "frame_rate: "},
      {[](CameraConfig& c) { c.trigger = "line"; },
       "trigger: expected free_run, software or hardware"},
      {[](CameraConfig& c) {
         c.trigger = "hardware";
         c.trigger_line = "";
       },
       "trigger_line: "},
      {[](CameraConfig& c) { c.packet_size = 100; }, "packet_size: "},
      {[](CameraConfig& c) { c.socket_buffer = -1; }, "socket_buffer: "},
      {[](CameraConfig& c) { c.buffer_count = 1; }, "buffer_count: expected 2-64 buffers, got 1"},
  };
  EXPECT_EQ(Good("aravis").Validate(), "");
  for (const auto& [spoil, key] : cases) {
    CameraConfig config = Good("aravis");
    spoil(config);
    EXPECT_THAT(config.Validate(), StartsWith(key));
  }
}

TEST(CameraConfigTest, ChecksDependOnTheBackend) {
  for (const std::string backend : {"aravis", "v4l2", "replay", "simulated"}) {
    EXPECT_EQ(Good(backend).Validate(), "") << backend;
  }
  CameraConfig v4l2 = Good("v4l2");
  v4l2.pixel_format = "RGB8";
  EXPECT_THAT(v4l2.Validate(), HasSubstr("for v4l2 YUYV, MJPG, MJPEG, RGB3 or BGR3"));
  CameraConfig replay = Good("replay");
  replay.trigger = "hardware";
  EXPECT_THAT(replay.Validate(), StartsWith("trigger: expected free_run or software for replay"));
  CameraConfig simulated = Good("simulated");
  simulated.pixel_format = "BayerRG8";
  EXPECT_THAT(simulated.Validate(), StartsWith("pixel_format: "));
}

TEST(CameraConfigTest, TriggerModes) {
  CameraConfig config = Good("aravis");
  config.trigger = "free_run";
  EXPECT_EQ(config.Trigger(), TriggerMode::kFreeRun);
  config.trigger = "software";
  EXPECT_EQ(config.Trigger(), TriggerMode::kSoftware);
  config.trigger = "hardware";
  EXPECT_EQ(config.Trigger(), TriggerMode::kHardware);
  config.trigger = "sometimes";
  EXPECT_THROW(config.Trigger(), std::invalid_argument);
}

TEST(CaptureOptionsTest, YamlErrorsNameTheFileTheCameraAndTheKey) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"cameras: [{name: cam0, backend: simulated}, {name: cam1, backend: v4l2, device: "
       "/dev/video0, "
       "pixel_format: RGB8}]",
       "capture.yaml: cameras[1].pixel_format: expected for v4l2"},
      {"cameras: [{name: cam0, backend: simulated}, {name: cam0, backend: simulated}]",
       "capture.yaml: cameras[1].name: expected a name no other camera has"},
      {"cameras: [{name: cam0, backend: simulated, device: other.yaml}]", "cameras[0].device: "},
      {"cameras: [{name: cam0, exposure: 3}]", "capture.yaml: cameras[0].exposure: unknown key"},
      {"trigger_rate_hz: 0", "capture.yaml: trigger_rate_hz: expected 0.1-1000 Hz"},
      {"compression: jpeg", "compression: expected none or png"},
      {"png_level: 10", "png_level: "},
      {"reconnect_interval_s: 0", "reconnect_interval_s: "},
      {"simulation: {trajectory: {loop_period: -1}}", "simulation.trajectory.loop_period"},
      {"simulation: {trajectory: {render: {ambient: 9}}}", "simulation.trajectory.render.ambient"},
      {"background: {frames: 0}", "background.frames: "},
  };
  for (const auto& [yaml, expected] : cases) {
    try {
      OptionsFromYamlText<CaptureServiceOptions>(yaml, "capture.yaml");
      ADD_FAILURE() << yaml << ": expected InputError";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(expected)) << yaml;
    }
  }
}

TEST(CaptureOptionsTest, CommandLineCamerasJoinOrOverrideTheConfig) {
  testing::TempDir dir("capture_options");
  const std::string path = (dir.path() / "capture.yaml").string();
  WriteFileAtomically(path,
                      "cameras:\n"
                      "  - {name: cam0, backend: aravis, device: 10.0.0.5, exposure_us: 900}\n"
                      "  - {name: cam1, backend: simulated}\n"
                      "trigger_rate_hz: 50\n");
  const CaptureServiceOptions options =
      LoadCaptureOptions(path, {"cam0=v4l2:/dev/video2", "cam2=simulated:"}, 12.5);
  ASSERT_EQ(options.cameras.size(), 3u);
  EXPECT_EQ(options.cameras[0].backend, "v4l2");
  EXPECT_EQ(options.cameras[0].device, "/dev/video2");
  EXPECT_EQ(options.cameras[0].pixel_format, "YUYV") << "the new backend's default format";
  EXPECT_EQ(options.cameras[0].exposure_us, 900.0) << "the other keys stay";
  EXPECT_EQ(options.cameras[2].name, "cam2");
  EXPECT_EQ(options.trigger_rate_hz, 12.5);
  EXPECT_EQ(LoadCaptureOptions(path, {}).trigger_rate_hz, 50.0);
}

TEST(CaptureOptionsTest, ACommandLineWithoutCamerasOrWithBadOnesIsAnInputError) {
  EXPECT_THAT(
      [] { LoadCaptureOptions("", {}); },
      ::testing::ThrowsMessage<InputError>(HasSubstr("cameras: expected at least one camera")));
  EXPECT_THAT(
      [] {
        LoadCaptureOptions("", {"cam0=simulated:", "cam1"});
      },
      ::testing::ThrowsMessage<InputError>(HasSubstr("--camera 'cam1'")));
  EXPECT_THAT([] { LoadCaptureOptions("", {"cam0=simulated:"}, 0.0); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("command line: trigger_rate_hz: ")));
  EXPECT_THAT([] { LoadCaptureOptions("/nonexistent/capture.yaml", {"cam0=simulated:"}); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("/nonexistent/capture.yaml")));
}

TEST(CaptureOptionsTest, TheShippedConfigIsValid) {
  const CaptureServiceOptions options =
      LoadCaptureOptions(std::string(SHAPESENSE_SOURCE_DIR) + "/config/capture.yaml", {});
  EXPECT_FALSE(options.cameras.empty());
}

TEST(CaptureOptionsTest, DocumentedYamlRoundTrips) {
  CaptureServiceOptions options;
  options.cameras = {ParseCameraSpec("cam0=aravis:127.0.0.1"),
                     ParseCameraSpec("cam1=v4l2:/dev/video0")};
  options.trigger_rate_hz = 42.0;
  options.simulation.trajectory.render.noise_sigma = 3.5;
  const std::string yaml = OptionsToDocumentedYaml(options);
  const CaptureServiceOptions back = OptionsFromYamlText<CaptureServiceOptions>(yaml, "round trip");
  ASSERT_EQ(back.cameras.size(), 2u);
  EXPECT_EQ(back.cameras[1].pixel_format, "YUYV");
  EXPECT_EQ(back.trigger_rate_hz, 42.0);
  EXPECT_EQ(back.simulation.trajectory.render.noise_sigma, 3.5);
}

}  // namespace
}  // namespace shapesense
