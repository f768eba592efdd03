#include "libs/silhouette/compact_silhouette.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "tests/libs/silhouette/synthetic_frame.h"

namespace shapesense {
namespace {

using testing::FrameSpec;
using testing::MakeFrame;

Silhouette Extracted(const FrameSpec& spec) {
  const testing::SyntheticFrame frame = MakeFrame(spec);
  Silhouette silhouette;
  SilhouetteExtractor(SilhouetteOptions{}).Extract(frame.image, frame.background, &silhouette);
  return silhouette;
}

CompactSilhouette CompactOf(const Silhouette& silhouette) {
  CompactSilhouette compact;
  CompactScratch scratch;
  Compact(silhouette, &compact, &scratch);
  return compact;
}

bool SameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

// Brute force: within kEdgeBandRadius (Chebyshev) of a mask pixel and of a
// pixel of the image outside the mask.
cv::Mat BandByDefinition(const cv::Mat& mask) {
  cv::Mat band(mask.size(), CV_8U, cv::Scalar(0));
  const int r = kEdgeBandRadius;
  for (int y = 0; y < mask.rows; ++y) {
    for (int x = 0; x < mask.cols; ++x) {
      bool near_inside = false;
      bool near_outside = false;
      for (int v = std::max(0, y - r); v <= std::min(mask.rows - 1, y + r); ++v) {
        for (int u = std::max(0, x - r); u <= std::min(mask.cols - 1, x + r); ++u) {
          (mask.at<uint8_t>(v, u) != 0 ? near_inside : near_outside) = true;
        }
      }
      if (near_inside && near_outside) band.at<uint8_t>(y, x) = 255;
    }
  }
  return band;
}

std::vector<FrameSpec> Specs() {
  std::vector<FrameSpec> specs;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    FrameSpec spec;
    spec.size = {320, 240};
    spec.tube_thickness = 8;
    spec.seed = seed;
    spec.second_tube = seed == 2;
    spec.curl = 0.5 * seed;
    specs.push_back(spec);
  }
  return specs;
}

TEST(CompactSilhouetteTest, ExpandsToTheMaskLabelsAndRunsExactly) {
  for (const FrameSpec& spec : Specs()) {
    const Silhouette original = Extracted(spec);
    ASSERT_GT(original.area, 0);
    const CompactSilhouette compact = CompactOf(original);
    ASSERT_EQ(Validate(compact), "");
    Silhouette expanded;
    Expand(compact, &expanded);
    EXPECT_TRUE(SameImage(expanded.mask, original.mask)) << "seed " << spec.seed;
    EXPECT_TRUE(SameImage(expanded.labels, original.labels)) << "seed " << spec.seed;
    EXPECT_EQ(expanded.area, original.area);
    EXPECT_EQ(expanded.bounds, original.bounds);
    ASSERT_EQ(expanded.runs.size(), original.runs.size());
    EXPECT_FALSE(compact.markers.empty()) << "the frames have tape";
  }
}

TEST(CompactSilhouetteTest, KeepsTheDifferenceExactlyOnTheBandAndNothingElse) {
  for (const FrameSpec& spec : Specs()) {
    const Silhouette original = Extracted(spec);
    Silhouette expanded;
    Expand(CompactOf(original), &expanded);
    const cv::Mat band = BandByDefinition(original.mask);
    cv::Mat kept;
    original.difference.copyTo(kept, band);
    EXPECT_TRUE(SameImage(expanded.difference, kept)) << "seed " << spec.seed;
    // The band is a thin ribbon along the outline, not the image.
    EXPECT_LT(cv::countNonZero(band), original.mask.total() / 4);
  }
}

TEST(CompactSilhouetteTest, ExpandingIntoAnEarlierExpansionLeavesNothingOfIt) {
  const std::vector<FrameSpec> specs = Specs();
  Silhouette reused;
  for (size_t i = 0; i < specs.size(); ++i) {
    const CompactSilhouette compact = CompactOf(Extracted(specs[i]));
    Expand(compact, &reused);
    Silhouette fresh;
    Expand(compact, &fresh);
    EXPECT_TRUE(SameImage(reused.mask, fresh.mask)) << i;
    EXPECT_TRUE(SameImage(reused.labels, fresh.labels)) << i;
    EXPECT_TRUE(SameImage(reused.difference, fresh.difference)) << i;
  }
}

TEST(CompactSilhouetteTest, AVgaFrameFitsWellInOneDatagram) {
  FrameSpec spec;  // 640x480, a long curved tube with tape
  const CompactSilhouette compact = CompactOf(Extracted(spec));
  const size_t bytes = 6 * (compact.mask.size() + compact.markers.size() + compact.band.size()) +
                       compact.band_difference.size();
  EXPECT_LT(bytes, 20'000u);
}

TEST(CompactSilhouetteTest, AnEmptySilhouetteStaysEmpty) {
  Silhouette empty;
  empty.mask = cv::Mat(48, 64, CV_8U, cv::Scalar(0));
  empty.labels = empty.mask.clone();
  empty.difference = empty.mask.clone();
  const CompactSilhouette compact = CompactOf(empty);
  ASSERT_EQ(Validate(compact), "");
  EXPECT_TRUE(compact.mask.empty() && compact.band.empty());
  Silhouette expanded;
  Expand(compact, &expanded);
  EXPECT_EQ(expanded.area, 0);
  EXPECT_TRUE(expanded.bounds.empty());
  EXPECT_EQ(expanded.mask.size(), cv::Size(64, 48));
}

CompactSilhouette Small() {
  CompactSilhouette compact;
  compact.width = 10;
  compact.height = 5;
  compact.mask = {{1, 2, 6}, {2, 2, 7}};
  compact.markers = {{2, 3, 5}};
  compact.band = {{1, 1, 3}};
  compact.band_difference = {9, 9};
  return compact;
}

TEST(CompactSilhouetteTest, ValidateNamesWhatIsMalformed) {
  ASSERT_EQ(Validate(Small()), "");
  const auto error_of = [](auto change) {
    CompactSilhouette compact = Small();
    change(compact);
    return Validate(compact);
  };
  EXPECT_NE(error_of([](CompactSilhouette& c) { c.width = 0; }).find("size"), std::string::npos);
  EXPECT_NE(error_of([](CompactSilhouette& c) { c.mask[1].x1 = 11; }).find("mask: run"),
            std::string::npos);
  EXPECT_NE(error_of([](CompactSilhouette& c) { c.mask[1].y = 5; }).find("outside"),
            std::string::npos);
  EXPECT_NE(error_of([](CompactSilhouette& c) {
              c.mask[1] = {1, 4, 8};
            }).find("overlapping"),
            std::string::npos);
  EXPECT_NE(error_of([](CompactSilhouette& c) {
              c.mask[1] = {0, 2, 3};
            }).find("raster order"),
            std::string::npos);
  EXPECT_NE(error_of([](CompactSilhouette& c) {
              c.markers[0] = {2, 6, 8};
            }).find("tape"),
            std::string::npos);
  EXPECT_NE(error_of([](CompactSilhouette& c) {
              c.band_difference.push_back(1);
            }).find("expected 2 difference values, got 3"),
            std::string::npos);
  EXPECT_NE(error_of([](CompactSilhouette& c) { c.band[0].x1 = 1; }).find("edge band"),
            std::string::npos);
}

}  // namespace
}  // namespace shapesense
