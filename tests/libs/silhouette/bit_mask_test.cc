#include "libs/silhouette/bit_mask.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

namespace shapesense {
namespace {

BitMask ToBitMask(const cv::Mat& mask) {
  BitMask bits;
  bits.Reset(mask.cols, mask.rows);
  for (int y = 0; y < mask.rows; ++y) {
    for (int x = 0; x < mask.cols; ++x) {
      if (mask.at<uint8_t>(y, x) != 0) bits.Set(x, y);
    }
  }
  return bits;
}

cv::Mat ToMat(const BitMask& bits) {
  cv::Mat mask = cv::Mat::zeros(bits.height(), bits.width(), CV_8U);
  for (int y = 0; y < bits.height(); ++y) {
    for (int x = 0; x < bits.width(); ++x) {
      if (bits.Get(x, y)) mask.at<uint8_t>(y, x) = 255;
    }
  }
  return mask;
}

bool PaddingIsClear(const BitMask& bits) {
  for (int y = 0; y < bits.height(); ++y) {
    if ((bits.Row(y)[bits.words_per_row() - 1] & ~bits.LastWordMask()) != 0) return false;
  }
  return true;
}

TEST(BitMaskTest, DilationAndErosionEqualOpenCvOnRandomMasks) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> size(1, 200);
  std::uniform_int_distribution<int> radius(1, 10);
  std::uniform_real_distribution<double> density(0.0, 1.0);
  BitMask scratch, out;
  for (int trial = 0; trial < 150; ++trial) {
    cv::Mat noise(size(rng), size(rng), CV_32F);
    cv::randu(noise, 0.0, 1.0);
    const cv::Mat mask = noise < density(rng);
    const int r = radius(rng);
    const cv::Mat square =
        cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * r + 1, 2 * r + 1));
    cv::Mat expected;
    cv::dilate(mask, expected, square);
    DilateSquare(ToBitMask(mask), r, &scratch, &out);
    ASSERT_EQ(cv::countNonZero(ToMat(out) ^ expected), 0) << mask.size() << " radius " << r;
    ASSERT_TRUE(PaddingIsClear(out));
    cv::erode(mask, expected, square);
    ErodeSquare(ToBitMask(mask), r, &scratch, &out);
    ASSERT_EQ(cv::countNonZero(ToMat(out) ^ expected), 0) << mask.size() << " radius " << r;
    ASSERT_TRUE(PaddingIsClear(out));
  }
}

TEST(BitMaskTest, RadiusZeroIsTheIdentity) {
  cv::Mat mask(30, 70, CV_8U);
  cv::randu(mask, 0, 2);
  mask *= 255;
  BitMask scratch, out;
  DilateSquare(ToBitMask(mask), 0, &scratch, &out);
  EXPECT_EQ(cv::countNonZero(ToMat(out) ^ mask), 0);
  ErodeSquare(ToBitMask(mask), 0, &scratch, &out);
  EXPECT_EQ(cv::countNonZero(ToMat(out) ^ mask), 0);
}

}  // namespace
}  // namespace shapesense
