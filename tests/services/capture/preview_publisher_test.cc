// Camera previews: the same triggers for every camera at most at the rate
// asked, small JPEGs that carry their frame's identity, never the pipeline's
// image itself.
#include "services/capture/preview_publisher.h"

#include <gtest/gtest.h>

#include <chrono>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "runtime/lcm/channels.h"

namespace shapesense {
namespace {

CameraFrame Frame(int64_t trigger_seq) {
  CameraFrame frame;
  frame.image = cv::Mat(480, 640, CV_8UC3, cv::Scalar(20, 200, 30));
  cv::circle(frame.image, {320, 240}, 50, cv::Scalar(0, 0, 255), -1);
  frame.trigger_seq = trigger_seq;
  frame.trigger_utime = 1'700'000'000'000'000 + trigger_seq;
  frame.frame_id = 1000 + trigger_seq;
  frame.device_timestamp_ns = 5;
  frame.host_utime = 1'700'000'000'000'100 + trigger_seq;
  return frame;
}

TEST(PreviewPublisherTest, EveryNthTriggerAtMostTheRateAsked) {
  PreviewOptions options;
  options.rate_hz = 10;
  EXPECT_EQ(PreviewEvery(options, 30.0), 3);
  EXPECT_EQ(PreviewEvery(options, 31.0), 4);
  EXPECT_EQ(PreviewEvery(options, 5.0), 1);
  options.rate_hz = 0;
  EXPECT_EQ(PreviewEvery(options, 30.0), 0);
  EXPECT_EQ(options.Validate(), "");
  options.width = 8;
  EXPECT_NE(options.Validate().find("width"), std::string::npos);
}

TEST(PreviewPublisherTest, APreviewIsASmallJpegWithItsFramesIdentity) {
  const image_t preview = PreviewMessage("cam1", Frame(42), PreviewOptions{}, 77);
  EXPECT_EQ(preview.camera, "cam1");
  EXPECT_EQ(preview.compression, static_cast<int>(image_t::COMPRESSION_JPEG));
  EXPECT_EQ(preview.trigger_seq, 42);
  EXPECT_EQ(preview.frame_id, 1042);
  EXPECT_EQ(preview.trigger_utime, Frame(42).trigger_utime);
  EXPECT_EQ(preview.header.utime, 77);
  EXPECT_EQ(preview.size, static_cast<int32_t>(preview.data.size()));
  EXPECT_LT(preview.size, 60'000) << "one datagram on the rig network";
  const cv::Mat decoded = cv::imdecode(preview.data, cv::IMREAD_COLOR);
  ASSERT_EQ(decoded.cols, 320);
  EXPECT_EQ(decoded.rows, 240);
  EXPECT_EQ(preview.width, 320);
  const cv::Vec3b centre = decoded.at<cv::Vec3b>(120, 160);
  EXPECT_GT(centre[2], 200) << "the red disc, downscaled, where it was";
}

TEST(PreviewPublisherTest, OnlyThePreviewedTriggersArePublishedForEveryCamera) {
  std::mutex mutex;
  std::map<std::string, std::vector<int64_t>> published;
  {
    PreviewPublisher previews(PreviewOptions{}, 30.0,
                              [&](const std::string& channel, image_t& message) {
                                std::lock_guard lock(mutex);
                                published[channel].push_back(message.trigger_seq);
                              });
    for (int64_t seq = 0; seq < 12; ++seq) {
      for (const char* camera : {"cam0", "cam1"}) {
        CameraFrame frame = Frame(seq);
        previews.Offer(camera, frame);
        frame.image.setTo(cv::Scalar(0, 0, 0));  // the backend reuses its buffer at once
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (previews.published() + previews.dropped() < 8 &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  std::lock_guard lock(mutex);
  for (const char* camera : {"cam0", "cam1"}) {
    const std::vector<int64_t>& seqs = published[channels::Preview(camera)];
    EXPECT_FALSE(seqs.empty()) << camera;
    for (const int64_t seq : seqs) EXPECT_EQ(seq % 3, 0) << camera << " trigger " << seq;
  }
}

}  // namespace
}  // namespace shapesense
