// Frame-set grouping, the truth message and the raw image encoding of the
// rig-sim, without a network.

#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <random>

#include "libs/sim/scene_generators.h"
#include "services/capture/aravis_camera.h"
#include "services/rig_sim/frame_set_clock.h"
#include "services/rig_sim/frame_set_truth.h"
#include "services/rig_sim/raw_image.h"

namespace shapesense {
namespace {

struct Fill {
  int64_t utime;
  int camera;
  int64_t round;  // the trigger round it answers
};

// Rounds of triggers every `period`; each camera answers a round up to 90% of
// a period late, and camera 0 now and then (`merge` probability) is stuck past
// the next round's trigger and answers both with one late image, as the fake
// camera does. (Were every camera stuck in the same round, the late image
// would be the round's first, and it could not tell that round from the
// previous one.)
std::vector<Fill> Rounds(int cameras, int rounds, int64_t period, double merge, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int64_t> delay(0, period * 9 / 10);
  std::bernoulli_distribution merges(merge);
  std::vector<Fill> fills;
  for (int camera = 0; camera < cameras; ++camera) {
    bool stuck = false;
    for (int round = 0; round < rounds; ++round) {
      const int64_t late = stuck ? period * 19 / 20 : delay(rng);
      stuck = camera == 0 && round > 0 && round + 2 < rounds && merges(rng);
      if (!stuck) fills.push_back({1'000'000 + round * period + late, camera, round});
    }
  }
  std::sort(fills.begin(), fills.end(),
            [](const Fill& a, const Fill& b) { return a.utime < b.utime; });
  return fills;
}

// Every image joins the set of the trigger round it answers, however late
// within the period, in any order, with merged triggers; a round's first
// image opens its set.
TEST(FrameSetClock, EveryImageJoinsTheSetOfTheRoundItAnswers) {
  for (uint32_t seed = 0; seed < 20; ++seed) {
    const int64_t period = 10'000 + seed * 5'000;
    FrameSetClock clock(3);
    std::vector<int64_t> opened_at(200, -1);
    for (const Fill& fill : Rounds(3, 200, period, 0.05, seed)) {
      // Every camera's acquisition started before the first round.
      const bool first = fill.round == 0;
      const FrameSetClock::Slot slot = clock.Assign(fill.camera, fill.utime, first ? 0 : -1);
      ASSERT_EQ(slot.seq, fill.round) << "seed " << seed << " camera " << fill.camera;
      if (opened_at[fill.round] < 0) {
        EXPECT_TRUE(slot.opened);
        opened_at[fill.round] = fill.utime;
      }
      EXPECT_EQ(slot.first_utime, opened_at[fill.round]);
    }
  }
}

// A camera whose acquisition starts late answers its first trigger at its
// next 100 ms poll, one image for every trigger sent meanwhile: that image
// belongs to the first of them, the next to the round it answers.
TEST(FrameSetClock, AFirstImageJoinsTheFirstSetSinceItsAcquisitionStarted) {
  FrameSetClock clock(2);
  EXPECT_EQ(clock.Assign(0, 1'000, 0).seq, 0);
  EXPECT_EQ(clock.Assign(0, 34'000).seq, 1);  // camera 1 starts at 20 ms
  EXPECT_EQ(clock.Assign(0, 67'000).seq, 2);
  const FrameSetClock::Slot late = clock.Assign(1, 95'000, 20'000);
  EXPECT_EQ(late.seq, 1);
  EXPECT_FALSE(late.opened);
  EXPECT_EQ(late.first_utime, 34'000);
  EXPECT_EQ(clock.Assign(1, 100'000).seq, 3) << "its next image answers the next round";
  EXPECT_EQ(clock.Assign(0, 100'500).seq, 3);
  EXPECT_EQ(clock.Assign(1, 250'000, 200'000).seq, 4) << "restarted after the last set: opens one";
}

TEST(FrameSetTruth, CarriesTheSceneAndTheExactCurvature) {
  const Rig rig = MakeSyntheticRig(SyntheticRigOptions{});
  TrajectoryOptions options;
  const TrajectoryPose pose = PoseAt(options, 3.3);
  const TubeScene scene = SceneOf(options, rig, pose);
  const shape_t truth = FrameSetTruth(scene, pose, 42, 1'234'567, 7, 2'000'000);
  EXPECT_TRUE(truth.valid);
  EXPECT_EQ(truth.trigger_seq, 42);
  EXPECT_EQ(truth.trigger_utime, 1'234'567);
  EXPECT_EQ(truth.header.seq, 7);
  ASSERT_EQ(truth.num_points, static_cast<int32_t>(truth.centerline.size()));
  ASSERT_GT(truth.num_points, 100);
  for (int i = 1; i < truth.num_points; ++i) {
    const Vec3 a(truth.centerline[i - 1].data()), b(truth.centerline[i].data());
    EXPECT_LE((b - a).norm(), 2.0);
    EXPECT_GT(truth.arc_length[i], truth.arc_length[i - 1]);
    EXPECT_DOUBLE_EQ(truth.curvature[i], CurvatureAt(pose, truth.arc_length[i]));
  }
  const Vec3 first(truth.centerline.front().data()), last(truth.centerline.back().data());
  EXPECT_LT((first - scene.centerline.front()).norm(), 1e-12);
  EXPECT_LT((last - scene.centerline.back()).norm(), 1e-12);
  EXPECT_LT((Vec3(truth.tip) - last).norm(), 1e-12);
  EXPECT_NEAR(truth.length, pose.length, 0.01);
  ASSERT_EQ(truth.num_markers, 3);
  EXPECT_NEAR(truth.marker_arc_length[1], options.tapes[1].position * pose.length, 1e-9);
}

cv::Mat RandomBgr(int rows, int cols, uint32_t seed) {
  cv::Mat image(rows, cols, CV_8UC3);
  cv::RNG(seed).fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

cv::Mat RoundTrip(const cv::Mat& bgr, const std::string& format) {
  const uint32_t code = AravisPixelFormatCode(format);
  std::vector<uint8_t> raw(bgr.total() * static_cast<size_t>(RawBytesPerPixel(code)));
  EXPECT_TRUE(EncodeRawImage(bgr, code, bgr.cols, bgr.rows, raw.data(), raw.size())) << format;
  return DecodeAravisImage(code, raw.data(), raw.size(), bgr.cols, bgr.rows);
}

TEST(EncodeRawImage, IsUndoneByTheAravisBackendsDecoding) {
  const cv::Mat bgr = RandomBgr(24, 32, 1);
  EXPECT_EQ(cv::norm(RoundTrip(bgr, "RGB8"), bgr, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(RoundTrip(bgr, "BGR8"), bgr, cv::NORM_INF), 0.0);
  cv::Mat grey;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(cv::norm(RoundTrip(bgr, "Mono8"), grey, cv::NORM_INF), 0.0);
  const cv::Mat uniform(24, 32, CV_8UC3, cv::Scalar(30, 140, 220));
  for (const std::string format : {"BayerRG8", "BayerGR8", "BayerGB8", "BayerBG8"}) {
    EXPECT_EQ(cv::norm(RoundTrip(uniform, format), uniform, cv::NORM_INF), 0.0) << format;
  }
}

TEST(EncodeRawImage, ResizesToTheBufferAndRefusesWhatItCannotWrite) {
  const cv::Mat bgr = RandomBgr(48, 64, 2);
  std::vector<uint8_t> raw(32 * 24 * 3);
  const uint32_t rgb8 = AravisPixelFormatCode("RGB8");
  EXPECT_TRUE(EncodeRawImage(bgr, rgb8, 32, 24, raw.data(), raw.size()));
  EXPECT_FALSE(EncodeRawImage(bgr, rgb8, 32, 25, raw.data(), raw.size())) << "buffer too small";
  EXPECT_FALSE(EncodeRawImage(bgr, 0x02100000u, 32, 24, raw.data(), raw.size())) << "unknown";
  std::vector<uint8_t> mono16(8 * 8 * 2);
  const cv::Mat white(8, 8, CV_8UC3, cv::Scalar(255, 255, 255));
  EXPECT_TRUE(EncodeRawImage(white, 0x01100007u, 8, 8, mono16.data(), mono16.size()));
  EXPECT_EQ(mono16[0], 0xff);
  EXPECT_EQ(mono16[1], 0xff);
}

}  // namespace
}  // namespace shapesense
