// DecodeAravisImage: GenICam buffers to OpenCV images, without a camera.

#include <gtest/gtest.h>

#include <array>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <utility>

#include "services/capture/aravis_camera.h"

namespace shapesense {
namespace {

// A Bayer mosaic of a BGR image; `tile` lists the 2x2 tile row by row, e.g.
// "RGGB" for GenICam BayerRG8 (R G R G ... / G B G B ...).
cv::Mat Mosaic(const cv::Mat& bgr, const std::string& tile) {
  auto channel = [](char c) { return c == 'B' ? 0 : c == 'G' ? 1 : 2; };
  cv::Mat raw(bgr.size(), CV_8UC1);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      raw.at<uint8_t>(y, x) = bgr.at<cv::Vec3b>(y, x)[channel(tile[2 * (y % 2) + x % 2])];
    }
  }
  return raw;
}

cv::Mat RandomImage(int rows, int cols, int type, uint32_t seed) {
  cv::Mat image(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

TEST(DecodeAravisImage, Mono8IsCopiedExactly) {
  const cv::Mat raw = RandomImage(48, 64, CV_8UC1, 1);
  const cv::Mat image =
      DecodeAravisImage(AravisPixelFormatCode("Mono8"), raw.data, raw.total(), raw.cols, raw.rows);
  ASSERT_EQ(image.type(), CV_8UC1);
  EXPECT_EQ(cv::norm(image, raw, cv::NORM_INF), 0.0);
  EXPECT_NE(image.data, raw.data) << "the image must not alias the camera's buffer";
}

TEST(DecodeAravisImage, Rgb8BecomesBgrAndBgr8StaysExact) {
  const cv::Mat bgr = RandomImage(30, 40, CV_8UC3, 2);
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  const cv::Mat from_rgb = DecodeAravisImage(AravisPixelFormatCode("RGB8"), rgb.data,
                                             rgb.total() * 3, rgb.cols, rgb.rows);
  const cv::Mat from_bgr = DecodeAravisImage(AravisPixelFormatCode("BGR8"), bgr.data,
                                             bgr.total() * 3, bgr.cols, bgr.rows);
  ASSERT_EQ(from_rgb.type(), CV_8UC3);
  EXPECT_EQ(cv::norm(from_rgb, bgr, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(from_bgr, bgr, cv::NORM_INF), 0.0);
}

// A uniform colour survives any demosaicing exactly, so a swapped pattern
// (red for blue, or green misplaced) shows as a wrong colour.
TEST(DecodeAravisImage, EveryBayerPatternGivesBackAUniformColour) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> level(0, 255);
  const std::pair<std::string, std::string> patterns[] = {
      {"BayerRG8", "RGGB"}, {"BayerGR8", "GRBG"}, {"BayerGB8", "GBRG"}, {"BayerBG8", "BGGR"}};
  for (const auto& [name, tile] : patterns) {
    for (int trial = 0; trial < 5; ++trial) {
      const cv::Vec3b colour(level(rng), level(rng), level(rng));
      const cv::Mat bgr(24, 32, CV_8UC3, cv::Scalar(colour[0], colour[1], colour[2]));
      const cv::Mat raw = Mosaic(bgr, tile);
      const cv::Mat image =
          DecodeAravisImage(AravisPixelFormatCode(name), raw.data, raw.total(), raw.cols, raw.rows);
      ASSERT_EQ(image.type(), CV_8UC3) << name;
      EXPECT_EQ(cv::norm(image, bgr, cv::NORM_INF), 0.0)
          << name << ": colour " << colour << " decoded as " << image.at<cv::Vec3b>(12, 16);
    }
  }
}

TEST(DecodeAravisImage, RejectsUnknownFormatsAndShortBuffers) {
  const cv::Mat raw = RandomImage(10, 10, CV_8UC3, 4);
  EXPECT_TRUE(
      DecodeAravisImage(0x01100007u /* Mono16 */, raw.data, raw.total() * 3, 10, 10).empty());
  EXPECT_TRUE(DecodeAravisImage(AravisPixelFormatCode("RGB8"), raw.data, 299, 10, 10).empty());
  EXPECT_TRUE(DecodeAravisImage(AravisPixelFormatCode("Mono8"), nullptr, 100, 10, 10).empty());
  EXPECT_TRUE(DecodeAravisImage(AravisPixelFormatCode("Mono8"), raw.data, 100, 0, 10).empty());
}

TEST(AravisPixelFormatCode, KnowsTheSupportedNamesOnly) {
  EXPECT_EQ(AravisPixelFormatCode("Mono8"), 0x01080001u);
  EXPECT_EQ(AravisPixelFormatCode("RGB8"), 0x02180014u);
  EXPECT_EQ(AravisPixelFormatCode("BayerRG8"), 0x01080009u);
  EXPECT_EQ(AravisPixelFormatCode("BayerBG8"), 0x0108000bu);
  EXPECT_EQ(AravisPixelFormatCode("YUYV"), 0u);
}

}  // namespace
}  // namespace shapesense
