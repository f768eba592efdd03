// Background medians: against a plain sort over random frames, and the
// removal of what passes through fewer than half the frames.
#include "libs/calibration/background.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace shapesense {
namespace {

cv::Mat RandomImage(cv::RNG& rng, int rows, int cols, int type) {
  cv::Mat image(rows, cols, type);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

TEST(MedianImageTest, MatchesASortPerPixelOverRandomFrames) {
  cv::RNG rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const int count = 1 + trial % 9;
    const int type = trial % 2 == 0 ? CV_8UC3 : CV_8UC1;
    std::vector<cv::Mat> frames(static_cast<size_t>(count));
    for (cv::Mat& frame : frames) frame = RandomImage(rng, 7, 5, type);
    const cv::Mat median = MedianImage(frames);
    ASSERT_EQ(median.type(), type);
    const int values_per_row = 5 * median.channels();
    for (int y = 0; y < 7; ++y) {
      for (int i = 0; i < values_per_row; ++i) {
        std::vector<int> values;
        values.reserve(frames.size());
        for (const cv::Mat& f : frames) values.push_back(f.ptr<uint8_t>(y)[i]);
        std::sort(values.begin(), values.end());
        const size_t half = values.size() / 2;
        const int expected =
            values.size() % 2 == 1 ? values[half] : (values[half - 1] + values[half] + 1) / 2;
        ASSERT_EQ(median.ptr<uint8_t>(y)[i], expected) << "trial " << trial;
      }
    }
  }
}

TEST(MedianImageTest, RemovesWhatPassesThroughFewerThanHalfTheFrames) {
  cv::RNG rng(6);
  const cv::Mat empty_scene = RandomImage(rng, 48, 64, CV_8UC3);
  std::vector<cv::Mat> frames;
  std::vector<double> fractions;
  for (int i = 0; i < 9; ++i) {
    cv::Mat frame = empty_scene.clone();
    // Someone walks through four of the nine frames, each time elsewhere.
    if (i % 2 == 1) frame(cv::Rect(6 * i, 4 * i, 20, 12)).setTo(cv::Scalar(0, 0, 255));
    frames.push_back(frame);
  }
  const cv::Mat median =
      MedianImage(frames, [&](double f, const std::string&) { fractions.push_back(f); });
  EXPECT_EQ(cv::norm(median, empty_scene, cv::NORM_INF), 0.0);
  ASSERT_FALSE(fractions.empty());
  EXPECT_EQ(fractions.back(), 1.0);
}

TEST(MedianImageTest, RefusesFramesOfDifferentSizesOrTypes) {
  EXPECT_THROW(MedianImage({}), std::invalid_argument);
  const cv::Mat a(4, 4, CV_8UC3), b(4, 5, CV_8UC3), c(4, 4, CV_8UC1), d(4, 4, CV_16UC3);
  EXPECT_THROW(MedianImage({a, b}), std::invalid_argument);
  EXPECT_THROW(MedianImage({a, c}), std::invalid_argument);
  EXPECT_THROW(MedianImage({d, d}), std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
