// Frames to image_t and back, raw and PNG; inconsistent messages decode to nothing.
#include "services/capture/image_message.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "tests/services/capture/capture_test_util.h"

namespace shapesense {
namespace {

using testing::SameImage;

CameraFrame Frame(const cv::Mat& image) {
  CameraFrame frame;
  frame.image = image;
  frame.trigger_seq = 12;
  frame.trigger_utime = 1'000'000;
  frame.host_utime = 1'004'500;
  frame.device_timestamp_ns = 77;
  frame.frame_id = 4242;
  frame.exposure_us = 900;
  frame.gain_db = 3;
  return frame;
}

TEST(ImageMessageTest, RandomImagesRoundTripRawAndPng) {
  std::mt19937 random(1);
  for (int i = 0; i < 12; ++i) {
    const int width = 1 + static_cast<int>(random() % 90),
              height = 1 + static_cast<int>(random() % 70);
    cv::Mat image = testing::RandomImage(width, height, static_cast<uint32_t>(i));
    if (i % 2 == 1) cv::cvtColor(image, image, cv::COLOR_BGR2GRAY);
    for (const ImageCompression compression : {ImageCompression::kNone, ImageCompression::kPng}) {
      const image_t message = ToImageMessage("cam3", Frame(image), i, 2'000'000, compression);
      EXPECT_EQ(message.width, width);
      EXPECT_EQ(message.height, height);
      EXPECT_EQ(message.pixel_format,
                static_cast<int>(i % 2 == 1 ? image_t::PIXEL_MONO8 : image_t::PIXEL_BGR8));
      EXPECT_EQ(message.size, static_cast<int32_t>(message.data.size()));
      EXPECT_TRUE(SameImage(testing::DecodedImage(message), image)) << width << "x" << height;
    }
  }
}

TEST(ImageMessageTest, CarriesTheFrameSetAndItsCaptureStage) {
  const image_t message = ToImageMessage("cam3", Frame(testing::RandomImage(8, 6, 1)), 5, 2'000'000,
                                         ImageCompression::kNone);
  EXPECT_EQ(message.camera, "cam3");
  EXPECT_EQ(message.header.seq, 5);
  EXPECT_EQ(message.header.utime, 2'000'000);
  EXPECT_EQ(message.trigger_seq, 12);
  EXPECT_EQ(message.trigger_utime, 1'000'000);
  EXPECT_EQ(message.host_utime, 1'004'500);
  EXPECT_EQ(message.device_timestamp_ns, 77);
  EXPECT_EQ(message.frame_id, 4242);
  EXPECT_EQ(message.exposure_us, 900.0f);
  EXPECT_EQ(message.gain_db, 3.0f);
  ASSERT_EQ(message.num_stage_times, 1);
  EXPECT_EQ(message.stage_times[0].stage, "capture");
  EXPECT_EQ(message.stage_times[0].duration_us, 4500);
  EXPECT_EQ(message.stage_times[0].end_utime, 1'004'500);
  CameraFrame untimed = Frame(testing::RandomImage(8, 6, 1));
  untimed.trigger_utime = 0;
  EXPECT_EQ(ToImageMessage("cam3", untimed, 0, 0, ImageCompression::kNone).trigger_utime, 1'004'500)
      << "no trigger time: the image's own";
}

TEST(ImageMessageTest, AViewIntoALargerImageIsPackedRowByRow) {
  const cv::Mat whole = testing::RandomImage(40, 30, 4);
  const cv::Mat view = whole(cv::Rect(5, 3, 17, 11));
  const image_t message = ToImageMessage("cam0", Frame(view), 0, 0, ImageCompression::kNone);
  EXPECT_EQ(message.row_stride, 17 * 3);
  EXPECT_TRUE(SameImage(testing::DecodedImage(message), view));
}

TEST(ImageMessageTest, OnlyEightBitMonoOrBgrIsPublished) {
  EXPECT_THROW(
      ToImageMessage("cam0", Frame(cv::Mat(4, 4, CV_16UC1)), 0, 0, ImageCompression::kNone),
      std::invalid_argument);
  EXPECT_THROW(ToImageMessage("cam0", Frame(cv::Mat()), 0, 0, ImageCompression::kNone),
               std::invalid_argument);
  EXPECT_THROW(ParseCompression("jpeg"), std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
