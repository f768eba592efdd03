// The replay backend: a dataset written by the test comes back pixel-exact,
// by trigger sequence or at a set rate, looping or not; a video file plays
// in order; a missing source is a CameraError naming it.
#include "services/capture/replay_camera.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "tests/services/capture/capture_test_util.h"

namespace shapesense {
namespace {

using ::testing::HasSubstr;
using testing::ReplayConfig;
using testing::SameImage;
using testing::TempDir;
constexpr auto kWait = std::chrono::milliseconds(500);

class ReplayCameraTest : public ::testing::Test {
 protected:
  ReplayCameraTest() : dir_("replay"), rig_(testing::SmallRig(2)) {
    images_ = testing::WriteRandomDataset(dir_.path(), rig_, 5);
  }

  CameraFrame GrabOne(CameraBackend& camera) {
    CameraFrame frame;
    EXPECT_TRUE(camera.Grab(kWait, &frame));
    return frame;
  }

  TempDir dir_;
  Rig rig_;
  std::vector<std::vector<cv::Mat>> images_;
};

TEST_F(ReplayCameraTest, TriggerSequenceIndexesTheFramesOfEveryCamera) {
  ReplayCamera cam0(ReplayConfig("cam0", dir_.path().string()));
  ReplayCamera cam1(ReplayConfig("cam1", dir_.path().string()));
  cam0.Open();
  cam1.Open();
  EXPECT_EQ(cam0.FrameCount(), 5u);
  for (const int64_t seq : {0, 3, 1, 4, 7, 12}) {  // looping: 7 is frame 2, 12 is frame 2
    cam0.Trigger(seq, 1000 + seq);
    cam1.Trigger(seq, 1000 + seq);
    const CameraFrame a = GrabOne(cam0);
    const CameraFrame b = GrabOne(cam1);
    EXPECT_TRUE(SameImage(a.image, images_[seq % 5][0])) << "seq " << seq;
    EXPECT_TRUE(SameImage(b.image, images_[seq % 5][1])) << "seq " << seq;
    EXPECT_EQ(a.trigger_seq, seq);
    EXPECT_EQ(a.trigger_utime, 1000 + seq);
    EXPECT_GE(a.host_utime, a.trigger_utime);
  }
  EXPECT_EQ(cam0.Stats().frames, 6);
}

TEST_F(ReplayCameraTest, WithoutLoopNothingComesAfterTheEnd) {
  CameraConfig config = ReplayConfig("cam1", dir_.path().string());
  config.loop = false;
  ReplayCamera camera(config);
  camera.Open();
  camera.Trigger(4, 1);
  EXPECT_TRUE(SameImage(GrabOne(camera).image, images_[4][1]));
  camera.Trigger(5, 2);
  CameraFrame frame;
  EXPECT_FALSE(camera.Grab(kWait, &frame));
}

TEST_F(ReplayCameraTest, FreeRunPlaysInOrderNoFasterThanTheRate) {
  CameraConfig config = ReplayConfig("cam0", dir_.path().string(), "free_run");
  config.frame_rate = 100.0;
  ReplayCamera camera(config);
  camera.Open();
  std::vector<CameraFrame> frames;
  for (int i = 0; i < 12; ++i) frames.push_back(GrabOne(camera));
  for (int i = 0; i < 12; ++i) {
    EXPECT_EQ(frames[i].frame_id, i);
    EXPECT_EQ(frames[i].trigger_seq, -1);
    EXPECT_TRUE(SameImage(frames[i].image, images_[i % 5][0])) << "frame " << i;
  }
  // Frame i is due 10 ms × i after the first; late is possible, early is not.
  EXPECT_GE(frames[11].trigger_utime - frames[0].trigger_utime, 110'000 - 1'000);
}

TEST_F(ReplayCameraTest, Mono8GivesGreyImages) {
  CameraConfig config = ReplayConfig("cam0", dir_.path().string());
  config.pixel_format = "Mono8";
  ReplayCamera camera(config);
  camera.Open();
  camera.Trigger(2, 1);
  cv::Mat grey;
  cv::cvtColor(images_[2][0], grey, cv::COLOR_BGR2GRAY);
  EXPECT_TRUE(SameImage(GrabOne(camera).image, grey));
}

TEST_F(ReplayCameraTest, MissingSourcesAreCameraErrorsNamingThem) {
  ReplayCamera missing(ReplayConfig("cam0", (dir_.path() / "nope").string()));
  try {
    missing.Open();
    FAIL() << "expected CameraError";
  } catch (const CameraError& e) {
    EXPECT_THAT(e.what(), HasSubstr("cam0: "));
    EXPECT_THAT(e.what(), HasSubstr("nope"));
  }
  ReplayCamera not_in_dataset(ReplayConfig("cam5", dir_.path().string()));
  EXPECT_THROW(not_in_dataset.Open(), CameraError);
  ReplayCamera not_a_dataset(ReplayConfig("cam0", (dir_.path() / "frames").string()));
  EXPECT_THROW(not_a_dataset.Open(), CameraError);
  EXPECT_FALSE(not_a_dataset.IsOpen());
  CameraFrame frame;
  EXPECT_THROW(not_a_dataset.Grab(kWait, &frame), CameraError);
}

TEST_F(ReplayCameraTest, ReopeningCountsAReconnectAndForgetsOldTriggers) {
  ReplayCamera camera(ReplayConfig("cam0", dir_.path().string()));
  camera.Open();
  camera.Trigger(1, 1);
  camera.Close();
  camera.Trigger(2, 2);  // closed: ignored
  camera.Open();
  CameraFrame frame;
  EXPECT_FALSE(camera.Grab(std::chrono::milliseconds(20), &frame));
  camera.Trigger(3, 3);
  EXPECT_EQ(GrabOne(camera).trigger_seq, 3);
  EXPECT_EQ(camera.Stats().reconnects, 1);
}

TEST(ReplayVideoTest, AVideoPlaysOneFramePerTriggerAndLoops) {
  TempDir dir("replay_video");
  const std::string path = (dir.path() / "clip.avi").string();
  std::vector<cv::Mat> originals;
  {
    cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0,
                           cv::Size(96, 72));
    ASSERT_TRUE(writer.isOpened());
    for (int i = 0; i < 4; ++i) {
      // Flat colours far apart: each frame is recognisable after JPEG.
      originals.emplace_back(72, 96, CV_8UC3, cv::Scalar(40 + 50 * i, 200 - 40 * i, 60 * i));
      writer.write(originals.back());
    }
  }
  ReplayCamera camera(ReplayConfig("cam0", path));
  camera.Open();
  for (int64_t seq = 0; seq < 7; ++seq) {
    camera.Trigger(seq, 100 + seq);
    CameraFrame frame;
    ASSERT_TRUE(camera.Grab(kWait, &frame)) << "seq " << seq;
    EXPECT_EQ(frame.trigger_seq, seq);
    ASSERT_EQ(frame.image.size(), cv::Size(96, 72));
    EXPECT_LT(cv::norm(frame.image, originals[seq % 4], cv::NORM_INF), 12.0) << "seq " << seq;
  }
}

}  // namespace
}  // namespace shapesense
