// The background command: the per-pixel median of N frames per camera,
// written where a dataset keeps its backgrounds.
#include "services/capture/background_capture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <thread>

#include "libs/camera/rig_yaml.h"
#include "libs/sim/tube_scene.h"
#include "runtime/file_io.h"
#include "tests/services/capture/capture_test_util.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

BackgroundCaptureArgs QuietArgs(CaptureServiceOptions options) {
  return {std::move(options), [](const std::string&) {}, {}};
}

TEST(BackgroundCaptureTest, WritesTheMedianOfTheFramesOfEachCamera) {
  TempDir dir("background_replay");
  const auto frames = testing::WriteRandomDataset(dir.path() / "set", testing::SmallRig(2), 7);
  CaptureServiceOptions options;
  options.cameras = {testing::ReplayConfig("cam0", (dir.path() / "set").string()),
                     testing::ReplayConfig("cam1", (dir.path() / "set").string())};
  options.trigger_rate_hz = 200.0;
  options.background.frames = 7;
  options.background.out = (dir.path() / "out" / "background").string();
  std::atomic<bool> stop{false};
  const std::vector<fs::path> written = RunBackgroundCapture(QuietArgs(options), stop);
  ASSERT_EQ(written.size(), 2u);
  std::mt19937 random(3);
  for (int camera = 0; camera < 2; ++camera) {
    EXPECT_EQ(written[camera],
              fs::path(options.background.out) / ("cam" + std::to_string(camera) + ".png"));
    const cv::Mat median = ReadBgrImage(written[camera]);
    ASSERT_EQ(median.size(), frames[0][camera].size());
    // Spot checks against a median computed here by sorting.
    for (int i = 0; i < 200; ++i) {
      const int x = static_cast<int>(random() % median.cols),
                y = static_cast<int>(random() % median.rows);
      const int c = static_cast<int>(random() % 3);
      std::array<int, 7> values{};
      for (size_t f = 0; f < values.size(); ++f)
        values[f] = frames[f][camera].at<cv::Vec3b>(y, x)[c];
      std::sort(values.begin(), values.end());
      const int got = median.at<cv::Vec3b>(y, x)[c];
      ASSERT_EQ(got, values[3]) << "pixel " << x << "," << y;
    }
  }
}

TEST(BackgroundCaptureTest, SimulatedCamerasShowTheBackdropAlone) {
  TempDir dir("background_sim");
  const Rig rig = testing::SmallRig(2);
  WriteFileAtomically(dir.path() / "rig.yaml", FormatRigYaml(rig));
  CaptureServiceOptions options;
  options.rig = (dir.path() / "rig.yaml").string();
  for (const std::string name : {"cam0", "cam1"}) {
    CameraConfig camera;
    camera.name = name;
    camera.backend = "simulated";
    options.cameras.push_back(camera);
  }
  options.trigger_rate_hz = 200.0;
  options.background.frames = 5;
  options.background.out = (dir.path() / "background").string();
  std::atomic<bool> stop{false};
  const std::vector<fs::path> written = RunBackgroundCapture(QuietArgs(options), stop);
  RenderOptions clean = options.simulation.trajectory.render;
  clean.noise_sigma = 0.0;
  TubeScene scene;  // any scene: only its background view is used
  scene.centerline = {rig.base_point, rig.base_point + Vec3(0, 0, 50)};
  const std::vector<RenderedView> views = RenderScene(rig, scene, clean, 0);
  for (size_t camera = 0; camera < 2; ++camera) {
    const cv::Mat median = ReadBgrImage(written[camera]);
    const double mean_error =
        cv::norm(median, views[camera].background, cv::NORM_L1) / median.total() / 3;
    EXPECT_LT(mean_error, 1.5) << "noise averaged out, and no manipulator";
    EXPECT_LE(cv::norm(median, views[camera].background, cv::NORM_INF), 12.0);
  }
}

// A software-triggered camera that loses its first trigger (as a camera
// just started can), then answers every trigger with a flat grey frame.
class FirstTriggerLost : public CameraBackend {
 public:
  explicit FirstTriggerLost(std::string name) : name_(std::move(name)) {}
  const std::string& name() const override { return name_; }
  void Open() override { open_ = true; }
  void Close() override { open_ = false; }
  bool IsOpen() const override { return open_; }
  void Trigger(int64_t seq, int64_t utime) override {
    ++triggers_;
    if (triggers_ > 1) pending_.push_back({seq, utime});
  }
  bool Grab(std::chrono::milliseconds timeout, CameraFrame* frame) override {
    if (pending_.empty()) {
      std::this_thread::sleep_for(std::min(timeout, std::chrono::milliseconds(20)));
      return false;
    }
    frame->image = cv::Mat(8, 8, CV_8UC3, cv::Scalar(90, 90, 90));
    frame->trigger_seq = pending_.front().first;
    frame->trigger_utime = pending_.front().second;
    pending_.erase(pending_.begin());
    return true;
  }
  CameraStats Stats() const override { return {}; }

 private:
  std::string name_;
  bool open_ = false;
  int triggers_ = 0;
  std::vector<std::pair<int64_t, int64_t>> pending_;
};

TEST(BackgroundCaptureTest, ALostTriggerIsSentAgain) {
  TempDir dir("background_lost_trigger");
  CaptureServiceOptions options;
  CameraConfig camera = testing::ReplayConfig("cam0", (dir.path() / "unused").string());
  camera.backend = "aravis";
  camera.trigger = "software";
  camera.width = 8;
  camera.height = 8;
  options.cameras = {camera};
  options.background.frames = 3;
  options.background.out = (dir.path() / "background").string();
  BackgroundCaptureArgs args = QuietArgs(options);
  args.make_backend = [](const CameraConfig& config, const BackendContext&) {
    return std::make_unique<FirstTriggerLost>(config.name);
  };
  std::atomic<bool> stop{false};
  const std::vector<fs::path> written = RunBackgroundCapture(args, stop);
  ASSERT_EQ(written.size(), 1u);
  EXPECT_EQ(ReadBgrImage(written[0]).at<cv::Vec3b>(4, 4), cv::Vec3b(90, 90, 90));
}

TEST(BackgroundCaptureTest, ACameraThatCannotOpenIsACameraError) {
  TempDir dir("background_missing");
  CaptureServiceOptions options;
  options.cameras = {testing::ReplayConfig("cam0", (dir.path() / "none").string())};
  options.background.out = (dir.path() / "background").string();
  std::atomic<bool> stop{false};
  EXPECT_THROW(RunBackgroundCapture(QuietArgs(options), stop), CameraError);
  EXPECT_FALSE(fs::exists(dir.path() / "background" / "cam0.png"));
}

}  // namespace
}  // namespace shapesense
