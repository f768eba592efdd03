// The rig-sim's truth message and raw image encoding, without a network.

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "libs/sim/scene_generators.h"
#include "runtime/lcm/truth_message.h"
#include "services/capture/aravis_camera.h"
#include "services/rig_sim/raw_image.h"

namespace shapesense {
namespace {

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
