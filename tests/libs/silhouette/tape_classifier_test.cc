#include "libs/silhouette/tape_classifier.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/libs/silhouette/reference_silhouette.h"

namespace shapesense {
namespace {

bool IsTape(const TapeColour& colour, const cv::Vec3b& bgr) {
  return TapeClassifier(colour).IsTape(&bgr[0]);
}

// Every one of the 2^24 colours decided as the floating-point rule decides
// it, for ranges that wrap through 0 or not, narrow and wide, with bounds
// between whole degrees.
TEST(TapeClassifierTest, EqualsTheFloatingPointRuleOnEveryColour) {
  const std::vector<TapeColour> colours = {
      TapeColour{},
      {{200.0, 260.0}, 0.25, 30},
      {{359.0, 1.0}, 0.1, 1},
      {{10.0, 350.0}, 0.9, 200},
      {{12.5, 47.25}, 0.55, 0},
  };
  for (const TapeColour& colour : colours) {
    const TapeClassifier classifier(colour);
    int64_t tape = 0;
    for (int b = 0; b < 256; ++b) {
      for (int g = 0; g < 256; ++g) {
        for (int r = 0; r < 256; ++r) {
          const cv::Vec3b pixel(static_cast<uint8_t>(b), static_cast<uint8_t>(g),
                                static_cast<uint8_t>(r));
          const bool expected = testing::ReferenceIsTape(pixel, colour);
          tape += expected;
          ASSERT_EQ(classifier.IsTape(&pixel[0]), expected) << pixel << " in " << Describe(colour);
        }
      }
    }
    EXPECT_GT(tape, 10'000) << Describe(colour);
  }
}

TEST(TapeClassifierTest, DefaultTakesRedsFromCrimsonToOrangeAndNotTheirMixes) {
  const TapeColour colour;
  EXPECT_TRUE(IsTape(colour, {30, 30, 200}));    // the renderer's tape, hue 0
  EXPECT_TRUE(IsTape(colour, {26, 22, 142}));    // dark red (35, 30, 190) at 75 %, hue 358
  EXPECT_TRUE(IsTape(colour, {64, 64, 121}));    // pale red (110, 110, 220) at 55 %, with noise
  EXPECT_TRUE(IsTape(colour, {20, 70, 230}));    // orange-red, hue 14
  EXPECT_TRUE(IsTape(colour, {70, 20, 200}));    // crimson, hue 343
  EXPECT_FALSE(IsTape(colour, {35, 102, 122}));  // tape half over the green backdrop, hue 46
  EXPECT_FALSE(IsTape(colour, {55, 55, 88}));    // a sixth tape, the rest body: saturation 0.375
  EXPECT_FALSE(IsTape(colour, {60, 60, 65}));    // the body
  EXPECT_FALSE(IsTape(colour, {40, 175, 45}));   // the backdrop
}

TEST(TapeClassifierTest, HueRangeWrapsThroughZeroWithBothEndsIncluded) {
  TapeColour colour;
  colour.hue_deg = {335.0, 25.0};
  EXPECT_TRUE(IsTape(colour, {0, 50, 120}));   // hue 25
  EXPECT_FALSE(IsTape(colour, {0, 51, 120}));  // hue 25.5
  EXPECT_TRUE(IsTape(colour, {50, 0, 120}));   // hue 335
  EXPECT_FALSE(IsTape(colour, {51, 0, 120}));  // hue 334.5
  EXPECT_TRUE(IsTape(colour, {0, 0, 120}));    // hue 0
  EXPECT_FALSE(IsTape(colour, {120, 0, 0}));   // blue, hue 240
  colour.hue_deg = {200.0, 260.0};             // the same bounds without wrapping
  EXPECT_TRUE(IsTape(colour, {120, 0, 0}));
  EXPECT_FALSE(IsTape(colour, {0, 0, 120}));
  colour.hue_deg = {25.0, 335.0};  // the complement of the wrapping range, ends included
  EXPECT_TRUE(IsTape(colour, {0, 50, 120}));
  EXPECT_TRUE(IsTape(colour, {120, 0, 0}));
  EXPECT_FALSE(IsTape(colour, {0, 0, 120}));
}

TEST(TapeClassifierTest, SaturationAndValueMinimaAreIncluded) {
  TapeColour colour;
  colour.min_saturation = 0.4;
  EXPECT_TRUE(IsTape(colour, {120, 120, 200}));   // saturation 0.4
  EXPECT_FALSE(IsTape(colour, {121, 121, 200}));  // 0.395
  colour.min_saturation = 0.55;
  EXPECT_FALSE(IsTape(colour, {110, 110, 220}));  // pale red: 0.5
  colour.min_value = 60;
  EXPECT_TRUE(IsTape(colour, {15, 15, 60}));
  EXPECT_FALSE(IsTape(colour, {15, 15, 59}));
  colour.min_value = 0;
  EXPECT_TRUE(IsTape(colour, {0, 0, 1}));
  EXPECT_FALSE(IsTape(colour, {0, 0, 0}));  // black has no hue
}

TEST(TapeClassifierTest, HueAndSaturationAreTheTextbookOnes) {
  const auto hue = [](uint8_t b, uint8_t g, uint8_t r) {
    const uint8_t bgr[3] = {b, g, r};
    return HueDeg(bgr);
  };
  EXPECT_DOUBLE_EQ(hue(0, 0, 255), 0.0);
  EXPECT_DOUBLE_EQ(hue(0, 255, 255), 60.0);
  EXPECT_DOUBLE_EQ(hue(0, 255, 0), 120.0);
  EXPECT_DOUBLE_EQ(hue(255, 0, 0), 240.0);
  EXPECT_DOUBLE_EQ(hue(255, 0, 255), 300.0);
  EXPECT_DOUBLE_EQ(hue(50, 0, 120), 335.0);
  EXPECT_DOUBLE_EQ(hue(90, 90, 90), 0.0);
  const uint8_t pale[3] = {110, 110, 220};
  EXPECT_DOUBLE_EQ(Saturation(pale), 0.5);
  const uint8_t black[3] = {0, 0, 0};
  EXPECT_DOUBLE_EQ(Saturation(black), 0.0);
}

TEST(TapeClassifierTest, DescribeGivesTheRangeAndMinima) {
  EXPECT_EQ(Describe(TapeColour{}), "[335, 25]° (saturation ≥ 0.4, value ≥ 60)");
}

TEST(TapeColourTest, ValidateNamesTheBadKey) {
  struct Case {
    const char* key;
    TapeColour colour;
  };
  const Case cases[] = {
      {"hue_deg", {{335.0, 360.0}, 0.4, 60}},
      {"hue_deg", {{-1.0, 25.0}, 0.4, 60}},
      {"hue_deg", {{std::nan(""), 25.0}, 0.4, 60}},
      {"hue_deg", {{20.0, 20.0}, 0.4, 60}},
      {"min_saturation", {{335.0, 25.0}, 0.0, 60}},
      {"min_saturation", {{335.0, 25.0}, 1.0, 60}},
      {"min_saturation", {{335.0, 25.0}, std::nan(""), 60}},
      {"min_value", {{335.0, 25.0}, 0.4, -1}},
      {"min_value", {{335.0, 25.0}, 0.4, 256}},
  };
  for (const Case& c : cases) {
    const std::string error = c.colour.Validate();
    EXPECT_EQ(error.rfind(std::string(c.key) + ": expected", 0), 0u) << error;
    EXPECT_THROW(TapeClassifier{c.colour}, std::invalid_argument) << c.key;
  }
  EXPECT_EQ(TapeColour{}.Validate(), "");
  const TapeColour empty{{20.0, 20.0}, 0.4, 60};
  EXPECT_EQ(empty.Validate(),
            "hue_deg: expected two different hues [from, to] (from > to wraps through 0), got "
            "[20, 20]");
}

}  // namespace
}  // namespace shapesense
