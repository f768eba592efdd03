#include "libs/silhouette/run_components.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "libs/silhouette/bit_mask.h"
#include "tests/libs/silhouette/reference_silhouette.h"

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

cv::Mat Paint(const std::vector<RowRun>& runs, cv::Size size) {
  cv::Mat painted = cv::Mat::zeros(size, CV_8U);
  for (const RowRun& run : runs) painted.row(run.y).colRange(run.x0, run.x1).setTo(255);
  return painted;
}

// Random masks of all densities and sizes (widths across 64-bit word
// boundaries), some smoothed into blobs so components are large and varied.
cv::Mat RandomMask(std::mt19937& rng) {
  std::uniform_int_distribution<int> size(1, 150);
  std::uniform_real_distribution<double> density(0.05, 0.7);
  cv::Mat noise(size(rng), size(rng), CV_32F);
  cv::randu(noise, 0.0, 1.0);
  if (rng() % 2 == 0) cv::blur(noise, noise, cv::Size(3, 3));
  return noise < density(rng);
}

TEST(RunComponentsTest, RunsCoverTheMaskExactly) {
  std::mt19937 rng(3);
  RunImage runs;
  for (int trial = 0; trial < 200; ++trial) {
    const cv::Mat mask = RandomMask(rng);
    ExtractRuns(ToBitMask(mask), &runs);
    ASSERT_EQ(runs.row_begin.size(), static_cast<size_t>(mask.rows) + 1);
    for (int y = 0; y < mask.rows; ++y) {
      for (int i = runs.row_begin[y]; i < runs.row_begin[y + 1]; ++i) {
        ASSERT_EQ(runs.runs[i].y, y);
        if (i > runs.row_begin[y]) {
          ASSERT_GT(runs.runs[i].x0, runs.runs[i - 1].x1);
        }
      }
    }
    ASSERT_EQ(cv::countNonZero(Paint(runs.runs, mask.size()) ^ mask), 0) << mask.size();
  }
}

TEST(RunComponentsTest, KeptPixelsAgreeWithOpenCvLabelling) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> min_area(0, 60);
  RunImage runs;
  ComponentScratch scratch;
  std::vector<RowRun> kept;
  for (int trial = 0; trial < 400; ++trial) {
    const cv::Mat mask = RandomMask(rng);
    const int area = trial % 10 == 0 ? 0 : min_area(rng);
    ExtractRuns(ToBitMask(mask), &runs);
    KeepManipulatorComponents(runs, area, &scratch, &kept);
    const cv::Mat expected = testing::ReferenceKept(mask, area);
    ASSERT_EQ(cv::countNonZero(Paint(kept, mask.size()) ^ expected), 0)
        << "trial " << trial << " size " << mask.size() << " min_area " << area;
  }
}

TEST(RunComponentsTest, EqualLargestComponentsKeepTheFirstInRasterOrder) {
  cv::Mat mask = cv::Mat::zeros(20, 20, CV_8U);
  mask(cv::Rect(10, 2, 3, 3)).setTo(255);  // first in raster order
  mask(cv::Rect(1, 10, 3, 3)).setTo(255);
  RunImage runs;
  ComponentScratch scratch;
  std::vector<RowRun> kept;
  ExtractRuns(ToBitMask(mask), &runs);
  KeepManipulatorComponents(runs, 100, &scratch, &kept);
  const cv::Mat painted = Paint(kept, mask.size());
  EXPECT_EQ(cv::countNonZero(painted), 9);
  EXPECT_EQ(painted.at<uint8_t>(2, 10), 255);
}

TEST(RunComponentsTest, DiagonalNeighboursAreOneComponent) {
  cv::Mat mask = cv::Mat::zeros(8, 130, CV_8U);
  for (int i = 0; i < 8; ++i) mask.at<uint8_t>(i, 60 + i) = 255;  // a diagonal across a word edge
  mask.at<uint8_t>(0, 0) = 255;
  RunImage runs;
  ComponentScratch scratch;
  std::vector<RowRun> kept;
  ExtractRuns(ToBitMask(mask), &runs);
  KeepManipulatorComponents(runs, 2, &scratch, &kept);
  EXPECT_EQ(kept.size(), 8u);
  EXPECT_EQ(cv::countNonZero(Paint(kept, mask.size()) ^ testing::ReferenceKept(mask, 2)), 0);
}

TEST(RunComponentsTest, EmptyMaskKeepsNothing) {
  BitMask empty;
  empty.Reset(70, 5);
  RunImage runs;
  ComponentScratch scratch;
  std::vector<RowRun> kept(3);
  ExtractRuns(empty, &runs);
  KeepManipulatorComponents(runs, 0, &scratch, &kept);
  EXPECT_TRUE(kept.empty());
}

}  // namespace
}  // namespace shapesense
