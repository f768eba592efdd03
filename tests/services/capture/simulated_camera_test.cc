// The simulated backend renders exactly what libs/sim's SceneRenderer
// renders for the world's scene at the trigger time; the built-in trajectory
// stays in the workspace and in view.
#include "services/capture/simulated_camera.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <set>

#include "tests/services/capture/capture_test_util.h"

namespace shapesense {
namespace {

using ::testing::HasSubstr;
using testing::SameImage;
constexpr int64_t kOrigin = 1'700'000'000'000'000;
constexpr auto kWait = std::chrono::milliseconds(2000);

CameraConfig SimulatedConfig(const std::string& name, const std::string& trigger = "software") {
  CameraConfig config;
  config.name = name;
  config.backend = "simulated";
  config.trigger = trigger;
  return config;
}

std::shared_ptr<const SimulatedWorld> MakeWorld(SimulationOptions options = {}) {
  return std::make_shared<SimulatedWorld>(testing::SmallRig(3), options, kOrigin);
}

RenderedView RenderAlone(const SimulatedWorld& world, size_t camera, int64_t seq, int64_t utime) {
  Rig own = world.rig();
  own.cameras = {world.rig().cameras[camera]};
  return SceneRenderer(own).Render(world.SceneAtUtime(utime), world.render(),
                                   world.ViewSeed(seq, camera))[0];
}

CameraFrame TriggerAndGrab(CameraBackend& camera, int64_t seq, int64_t utime) {
  camera.Trigger(seq, utime);
  CameraFrame frame;
  EXPECT_TRUE(camera.Grab(kWait, &frame));
  return frame;
}

TEST(SimulatedCameraTest, ImagesAreSceneRenderersViewAtTheTriggerTime) {
  const auto world = MakeWorld();
  SimulatedCamera camera(SimulatedConfig("cam1"), world);
  camera.Open();
  for (const int64_t seq : {0, 1, 17}) {
    const int64_t utime = kOrigin + seq * 333'333;
    const CameraFrame frame = TriggerAndGrab(camera, seq, utime);
    EXPECT_TRUE(SameImage(frame.image, RenderAlone(*world, 1, seq, utime).image)) << "seq " << seq;
    EXPECT_EQ(frame.trigger_seq, seq);
    EXPECT_EQ(frame.trigger_utime, utime);
    EXPECT_EQ(frame.image.size(), cv::Size(96, 72));
  }
}

TEST(SimulatedCameraTest, WithoutNoiseAViewAloneIsTheViewInTheWholeRig) {
  SimulationOptions options;
  options.trajectory.render.noise_sigma = 0.0;
  const auto world = MakeWorld(options);
  const int64_t utime = kOrigin + 700'000;
  const std::vector<RenderedView> rig_views =
      SceneRenderer(world->rig()).Render(world->SceneAtUtime(utime), options.trajectory.render, 0);
  for (size_t i = 0; i < 3; ++i) {
    SimulatedCamera camera(SimulatedConfig("cam" + std::to_string(i)), world);
    camera.Open();
    EXPECT_TRUE(SameImage(TriggerAndGrab(camera, 4, utime).image, rig_views[i].image))
        << "cam" << i;
  }
}

TEST(SimulatedCameraTest, NoiseDiffersBetweenCamerasAndFramesButRepeatsForTheSameOnes) {
  const auto world = MakeWorld();
  std::set<uint32_t> seeds;
  for (int64_t seq = 0; seq < 50; ++seq) {
    for (size_t camera = 0; camera < 3; ++camera) seeds.insert(world->ViewSeed(seq, camera));
  }
  EXPECT_EQ(seeds.size(), 150u);
  EXPECT_EQ(world->ViewSeed(9, 2), MakeWorld()->ViewSeed(9, 2));
  SimulationOptions other;
  other.seed = 1;
  EXPECT_NE(world->ViewSeed(9, 2), MakeWorld(other)->ViewSeed(9, 2));
}

TEST(SimulatedCameraTest, WithoutTheManipulatorItIsTheBackground) {
  SimulationOptions options;
  options.show_manipulator = false;
  const auto world = MakeWorld(options);
  SimulatedCamera camera(SimulatedConfig("cam2"), world);
  camera.Open();
  EXPECT_TRUE(SameImage(TriggerAndGrab(camera, 3, kOrigin).image,
                        RenderAlone(*world, 2, 3, kOrigin).background));
}

TEST(SimulatedCameraTest, Mono8AndFreeRun) {
  const auto world = MakeWorld();
  CameraConfig config = SimulatedConfig("cam0", "free_run");
  config.pixel_format = "Mono8";
  config.frame_rate = 200.0;
  SimulatedCamera camera(config, world);
  camera.Open();
  for (int64_t i = 0; i < 3; ++i) {
    CameraFrame frame;
    ASSERT_TRUE(camera.Grab(kWait, &frame));
    EXPECT_EQ(frame.frame_id, i);
    EXPECT_EQ(frame.trigger_seq, -1);
    cv::Mat grey;
    cv::cvtColor(RenderAlone(*world, 0, i, frame.trigger_utime).image, grey, cv::COLOR_BGR2GRAY);
    EXPECT_TRUE(SameImage(frame.image, grey)) << "frame " << i;
  }
}

TEST(SimulatedCameraTest, ACameraTheRigLacksIsACameraError) {
  SimulatedCamera camera(SimulatedConfig("cam7"), MakeWorld());
  try {
    camera.Open();
    FAIL() << "expected CameraError";
  } catch (const CameraError& e) {
    EXPECT_THAT(e.what(), HasSubstr("cam7"));
    EXPECT_THAT(e.what(), HasSubstr("cam0, cam1, cam2"));
  }
  EXPECT_FALSE(camera.IsOpen());
}

TEST(SimulatedCameraTest, TheSceneIsTheRigSimulatorsAtTheTriggerTime) {
  const auto world = MakeWorld();
  for (const double t : {0.0, 1.3, 5.2, 9.7}) {
    const int64_t utime = kOrigin + static_cast<int64_t>(t * 1e6);
    const TubeScene scene = world->SceneAtUtime(utime);
    const TubeScene expected = SceneAt(world->options().trajectory, world->rig(), t);
    ASSERT_EQ(scene.centerline.size(), expected.centerline.size());
    EXPECT_LT((scene.centerline.back() - expected.centerline.back()).norm(), 1e-9) << t;
  }
}

}  // namespace
}  // namespace shapesense
