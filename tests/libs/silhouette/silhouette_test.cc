#include "libs/silhouette/silhouette.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/libs/silhouette/reference_silhouette.h"
#include "tests/libs/silhouette/synthetic_frame.h"

namespace shapesense {
namespace {

using testing::FrameSpec;
using testing::MakeFrame;
using testing::SyntheticFrame;

int Count(const cv::Mat& mask) { return cv::countNonZero(mask); }

double IntersectionOverUnion(const cv::Mat& a, const cv::Mat& b) {
  return static_cast<double>(Count(a & b)) / Count(a | b);
}

double Perimeter(const cv::Mat& mask) {
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask.clone(), contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
  double length = 0.0;
  for (const auto& contour : contours) length += cv::arcLength(contour, true);
  return length;
}

Silhouette ExtractWith(const SilhouetteOptions& options, const SyntheticFrame& frame) {
  Silhouette silhouette;
  SilhouetteExtractor(options).Extract(frame.image, frame.background, &silhouette);
  return silhouette;
}

TEST(SilhouetteTest, MaskMatchesTheDrawnTube) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    FrameSpec spec;
    spec.seed = seed;
    spec.curl = 0.4 * seed;
    spec.tube_thickness = 7 + static_cast<int>(seed);
    const SyntheticFrame frame = MakeFrame(spec);
    const Silhouette silhouette = ExtractWith(SilhouetteOptions{}, frame);
    EXPECT_GE(IntersectionOverUnion(silhouette.mask, frame.tube), 0.98) << "seed " << seed;
    const int growth = Count(silhouette.mask) - Count(frame.tube);
    EXPECT_LE(growth, 0.5 * Perimeter(frame.tube)) << "seed " << seed;
  }
}

TEST(SilhouetteTest, ShadowIsRejectedByTheTestAndKeptWithoutIt) {
  const SyntheticFrame frame = MakeFrame(FrameSpec{});
  ASSERT_GT(Count(frame.shadow), 1000);
  const Silhouette with_test = ExtractWith(SilhouetteOptions{}, frame);
  EXPECT_LE(Count(with_test.mask & frame.shadow), 0.01 * Count(frame.shadow));
  SilhouetteOptions no_test;
  no_test.shadow_max_angle_deg = 0.0;
  const Silhouette without_test = ExtractWith(no_test, frame);
  EXPECT_GE(Count(without_test.mask & frame.shadow), 0.95 * Count(frame.shadow));
}

TEST(SilhouetteTest, ShadowDarkerThanTheDarkestAllowedIsForeground) {
  FrameSpec spec;
  spec.shadow_scale = 0.2;
  const SyntheticFrame frame = MakeFrame(spec);
  SilhouetteOptions options;
  options.shadow_min_brightness_ratio = 0.3;
  const Silhouette silhouette = ExtractWith(options, frame);
  EXPECT_GE(Count(silhouette.mask & frame.shadow), 0.95 * Count(frame.shadow));
}

TEST(SilhouetteTest, ClosingFillsSmallHolesInTheTube) {
  FrameSpec spec;
  spec.holes = 20;
  const SyntheticFrame frame = MakeFrame(spec);
  ASSERT_GT(Count(frame.holes), 20);
  const Silhouette closed = ExtractWith(SilhouetteOptions{}, frame);
  EXPECT_EQ(Count(frame.holes & ~closed.mask), 0);
  SilhouetteOptions no_dilation;
  no_dilation.dilation_radius = 0;
  const Silhouette open = ExtractWith(no_dilation, frame);
  EXPECT_GT(Count(frame.holes & ~open.mask), Count(frame.holes) / 2);
}

TEST(SilhouetteTest, DilationWithoutErosionGrowsTheMask) {
  const SyntheticFrame frame = MakeFrame(FrameSpec{});
  SilhouetteOptions options;
  options.erode_after_dilation = false;
  const Silhouette dilated = ExtractWith(options, frame);
  const Silhouette closed = ExtractWith(SilhouetteOptions{}, frame);
  EXPECT_EQ(Count(closed.mask & ~dilated.mask), 0);
  EXPECT_GT(Count(dilated.mask), Count(closed.mask) + 0.5 * Perimeter(frame.tube));
}

TEST(SilhouetteTest, SmallBlobsAreDroppedUnlessTheAreaLimitIsZero) {
  const SyntheticFrame frame = MakeFrame(FrameSpec{});
  ASSERT_GT(Count(frame.blobs), 10);
  EXPECT_EQ(Count(ExtractWith(SilhouetteOptions{}, frame).mask & frame.blobs), 0);
  SilhouetteOptions keep_all;
  keep_all.min_component_area = 0;
  EXPECT_EQ(Count(ExtractWith(keep_all, frame).mask & frame.blobs), Count(frame.blobs));
}

TEST(SilhouetteTest, LargestComponentIsKeptEvenBelowTheAreaLimit) {
  const SyntheticFrame frame = MakeFrame(FrameSpec{});
  SilhouetteOptions options;
  options.min_component_area = 10'000'000;
  const Silhouette silhouette = ExtractWith(options, frame);
  EXPECT_GE(IntersectionOverUnion(silhouette.mask, frame.tube), 0.98);
  EXPECT_EQ(Count(silhouette.mask & frame.blobs), 0);
}

TEST(SilhouetteTest, SecondLargeComponentIsKept) {
  FrameSpec spec;
  spec.second_tube = true;
  const SyntheticFrame frame = MakeFrame(spec);
  const Silhouette silhouette = ExtractWith(SilhouetteOptions{}, frame);
  EXPECT_GE(IntersectionOverUnion(silhouette.mask, frame.tube), 0.98);
  cv::Mat second = cv::Mat::zeros(frame.tube.size(), CV_8U);
  second(cv::Rect(frame.tube.cols - 60, 0, 60, 160)).setTo(255);
  second &= frame.tube;
  ASSERT_GT(Count(second), 500);
  EXPECT_GE(Count(silhouette.mask & second), 0.98 * Count(second));
}

TEST(SilhouetteTest, TapeIsLabelledAsMarkerOnlyInsideTheMask) {
  const SyntheticFrame frame = MakeFrame(FrameSpec{});
  const Silhouette silhouette = ExtractWith(SilhouetteOptions{}, frame);
  const cv::Mat marker = silhouette.labels == kLabelMarker;
  const cv::Mat body = silhouette.labels == kLabelBody;
  const cv::Mat tape = frame.tape & ~frame.holes;
  ASSERT_GT(Count(tape), 100);
  EXPECT_GE(Count(marker & tape), 0.99 * Count(tape));
  EXPECT_EQ(Count(marker & ~frame.tape), 0);
  EXPECT_EQ(Count((marker | body) ^ silhouette.mask), 0);
  EXPECT_EQ(Count((silhouette.labels == kLabelNone) & silhouette.mask), 0);
}

TEST(SilhouetteTest, MarkerColourRuleFollowsTheOptions) {
  // Random colours; the background's green is 128 away from every pixel's,
  // so everything is foreground.
  cv::Mat image(256, 256, CV_8UC3);
  cv::randu(image, 0, 256);
  cv::Mat background(image.size(), CV_8UC3, cv::Scalar::all(0));
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      background.at<cv::Vec3b>(y, x)[1] = image.at<cv::Vec3b>(y, x)[1] ^ 128;
    }
  }
  SilhouetteOptions options;
  options.shadow_max_angle_deg = 0.0;
  options.tape = {{300.0, 40.0}, 0.3, 50};
  Silhouette silhouette;
  SilhouetteExtractor(options).Extract(image, background, &silhouette);
  int tape = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const cv::Vec3b pixel = image.at<cv::Vec3b>(y, x);
      const bool expected = testing::ReferenceIsTape(pixel, options.tape);
      tape += expected;
      ASSERT_EQ(silhouette.labels.at<uint8_t>(y, x), expected ? kLabelMarker : kLabelBody)
          << "pixel " << pixel;
    }
  }
  EXPECT_GT(tape, 1000) << "the colours should hold tape for the test to label";
}

cv::Mat GreenDifference(const cv::Mat& image, const cv::Mat& background) {
  cv::Mat green, background_green, difference;
  cv::extractChannel(image, green, 1);
  cv::extractChannel(background, background_green, 1);
  cv::absdiff(green, background_green, difference);
  return difference;
}

TEST(SilhouetteTest, DifferenceIsTheRawGreenDifference) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> size(1, 300);
  const SilhouetteExtractor extractor{SilhouetteOptions{}};
  Silhouette silhouette;
  for (int trial = 0; trial < 20; ++trial) {
    // A region of a larger image, so rows are not contiguous.
    cv::Mat whole(size(rng) + 2, size(rng) + 2, CV_8UC3);
    cv::Mat background_whole(whole.size(), CV_8UC3);
    cv::randu(whole, 0, 256);
    cv::randu(background_whole, 0, 256);
    const cv::Rect region(1, 1, whole.cols - 2, whole.rows - 2);
    const cv::Mat image = whole(region);
    const cv::Mat background = background_whole(region);
    extractor.Extract(image, background, &silhouette);
    ASSERT_EQ(silhouette.difference.size(), image.size());
    EXPECT_EQ(cv::norm(silhouette.difference, GreenDifference(image, background), cv::NORM_INF),
              0.0)
        << image.size();
  }
}

// The reference method step by step with OpenCV: grey-scale dilation of the
// difference, threshold, erosion.
cv::Mat ReferenceClosing(const cv::Mat& difference, const SilhouetteOptions& options) {
  const int r = options.dilation_radius;
  const cv::Mat square = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * r + 1, 2 * r + 1));
  cv::Mat dilated, mask;
  cv::dilate(difference, dilated, square);
  mask = dilated > options.threshold;
  if (options.erode_after_dilation) cv::erode(mask, mask, square);
  return mask;
}

TEST(SilhouetteTest, BitmapClosingEqualsGreyScaleDilationThenThreshold) {
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> size(1, 200);
  std::uniform_real_distribution<double> density(0.0, 0.6);
  for (int trial = 0; trial < 60; ++trial) {
    // Random specks of foreground (green far from the backdrop's) of a random density.
    const cv::Size image_size(size(rng), size(rng));
    cv::Mat noise(image_size, CV_32F);
    cv::randu(noise, 0.0, 1.0);
    const cv::Mat foreground = noise < density(rng);
    cv::Mat image(image_size, CV_8UC3, cv::Scalar(40, 175, 45));
    image.setTo(cv::Scalar(60, 60, 60), foreground);
    const cv::Mat background(image_size, CV_8UC3, cv::Scalar(40, 175, 45));
    SilhouetteOptions options;
    options.shadow_max_angle_deg = 0.0;
    options.min_component_area = 0;
    options.dilation_radius = trial % 4;
    options.erode_after_dilation = trial % 3 != 0;
    Silhouette silhouette;
    SilhouetteExtractor(options).Extract(image, background, &silhouette);
    const cv::Mat expected = ReferenceClosing(GreenDifference(image, background), options);
    ASSERT_EQ(Count(silhouette.mask ^ expected), 0)
        << image_size << " radius " << options.dilation_radius << " erode "
        << options.erode_after_dilation;
  }
}

// Random frames and options (shadow test off; its decisions are compared in
// the next test): the fast extractor must give the reference's mask and labels
// pixel for pixel.
TEST(SilhouetteTest, EqualsTheStepByStepReferenceOnRandomFramesAndOptions) {
  std::mt19937 rng(21);
  std::uniform_int_distribution<int> radius(0, 3);
  std::uniform_int_distribution<int> area(0, 3000);
  std::uniform_int_distribution<int> thickness(3, 14);
  std::uniform_real_distribution<double> curl(0.0, 2.0);
  for (unsigned trial = 0; trial < 12; ++trial) {
    FrameSpec spec;
    spec.seed = 100 + trial;
    spec.size = trial % 3 == 0 ? cv::Size(333, 171) : cv::Size(640, 480);
    spec.tube_thickness = thickness(rng);
    spec.curl = curl(rng);
    spec.second_tube = trial % 2 == 0;
    spec.noise_sigma = 2.0 + trial;
    const SyntheticFrame frame = MakeFrame(spec);
    SilhouetteOptions options;
    options.shadow_max_angle_deg = 0.0;
    options.dilation_radius = radius(rng);
    options.erode_after_dilation = trial % 4 != 1;
    options.min_component_area = area(rng);
    options.threshold = 15 + static_cast<int>(trial) * 3;
    const Silhouette silhouette = ExtractWith(options, frame);
    cv::Mat mask, labels;
    testing::ReferenceSilhouette(frame.image, frame.background, options, &mask, &labels);
    ASSERT_EQ(Count(silhouette.mask ^ mask), 0) << "trial " << trial;
    ASSERT_EQ(Count(silhouette.labels != labels), 0) << "trial " << trial;
  }
}

TEST(SilhouetteTest, ShadowDecisionsEqualTheReferenceAwayFromTheLimits) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> angle(1.0, 20.0);
  std::uniform_real_distribution<double> ratio(0.0, 0.9);
  std::uniform_real_distribution<double> shadow_scale(0.2, 0.8);
  int rejected = 0;
  for (unsigned trial = 0; trial < 8; ++trial) {
    FrameSpec spec;
    spec.seed = 200 + trial;
    spec.size = cv::Size(320, 240);
    spec.tube_thickness = 6;
    spec.shadow_offset = cv::Point(8, 6);
    spec.shadow_scale = shadow_scale(rng);
    spec.noise_sigma = 1.0 + trial;
    const SyntheticFrame frame = MakeFrame(spec);
    SilhouetteOptions options;  // no closing, no components: the mask is the candidates
    options.dilation_radius = 0;
    options.min_component_area = 0;
    options.shadow_max_angle_deg = angle(rng);
    options.shadow_min_brightness_ratio = ratio(rng);
    const Silhouette silhouette = ExtractWith(options, frame);
    cv::Mat mask, labels;
    testing::ReferenceSilhouette(frame.image, frame.background, options, &mask, &labels);
    const cv::Mat differing = mask ^ silhouette.mask;
    std::vector<cv::Point> points;
    cv::findNonZero(differing, points);
    for (const cv::Point& p : points) {
      EXPECT_TRUE(testing::NearShadowLimit(frame.image.at<cv::Vec3b>(p),
                                           frame.background.at<cv::Vec3b>(p), options))
          << "trial " << trial << " at " << p;
    }
    rejected += Count((silhouette.difference > options.threshold) & ~silhouette.mask);
  }
  EXPECT_GT(rejected, 1000) << "the frames should hold shadow for the test to reject";
}

TEST(SilhouetteTest, TubeLeavingTheImageKeepsItsEndUnderTheClosing) {
  const SyntheticFrame frame = MakeFrame(FrameSpec{});
  const Silhouette silhouette = ExtractWith(SilhouetteOptions{}, frame);
  const int last = frame.tube.rows - 1;
  ASSERT_GT(Count(frame.tube.row(last)), 5);
  EXPECT_EQ(Count(frame.tube.row(last) & ~silhouette.mask.row(last)), 0);
}

TEST(SilhouetteTest, AreaBoundsAndRunsDescribeTheMask) {
  const SyntheticFrame frame = MakeFrame(FrameSpec{});
  const Silhouette silhouette = ExtractWith(SilhouetteOptions{}, frame);
  EXPECT_EQ(silhouette.area, Count(silhouette.mask));
  EXPECT_EQ(silhouette.bounds, cv::boundingRect(silhouette.mask));
  cv::Mat painted = cv::Mat::zeros(silhouette.mask.size(), CV_8U);
  for (const RowRun& run : silhouette.runs) {
    ASSERT_LT(run.x0, run.x1);
    painted.row(run.y).colRange(run.x0, run.x1).setTo(255);
  }
  EXPECT_EQ(Count(painted ^ silhouette.mask), 0);
}

TEST(SilhouetteTest, ImageEqualToTheBackgroundGivesAnEmptySilhouette) {
  const SyntheticFrame frame = MakeFrame(FrameSpec{});
  Silhouette silhouette;
  SilhouetteExtractor(SilhouetteOptions{}).Extract(frame.background, frame.background, &silhouette);
  EXPECT_EQ(Count(silhouette.mask), 0);
  EXPECT_EQ(Count(silhouette.labels), 0);
  EXPECT_EQ(silhouette.area, 0);
  EXPECT_TRUE(silhouette.bounds.empty());
}

TEST(SilhouetteTest, ReusedOutputGivesTheSameResultWithoutReallocating) {
  FrameSpec first_spec;
  FrameSpec second_spec;
  second_spec.seed = 2;
  second_spec.curl = 1.5;
  const SyntheticFrame first = MakeFrame(first_spec);
  const SyntheticFrame second = MakeFrame(second_spec);
  const SilhouetteExtractor extractor{SilhouetteOptions{}};
  Silhouette reused;
  extractor.Extract(first.image, first.background, &reused);
  const uint8_t* mask_data = reused.mask.data;
  const uint8_t* labels_data = reused.labels.data;
  extractor.Extract(second.image, second.background, &reused);
  EXPECT_EQ(reused.mask.data, mask_data);
  EXPECT_EQ(reused.labels.data, labels_data);
  const Silhouette fresh = ExtractWith(SilhouetteOptions{}, second);
  EXPECT_EQ(Count(reused.mask ^ fresh.mask), 0);
  EXPECT_EQ(Count(reused.labels != fresh.labels), 0);
  // A smaller image into the same output.
  const cv::Rect corner(0, 0, 200, 150);
  extractor.Extract(second.image(corner), second.background(corner), &reused);
  Silhouette corner_fresh;
  extractor.Extract(second.image(corner).clone(), second.background(corner).clone(), &corner_fresh);
  EXPECT_EQ(reused.mask.size(), corner.size());
  EXPECT_EQ(Count(reused.mask ^ corner_fresh.mask), 0);
}

TEST(SilhouetteTest, MismatchedInputsThrowNamingTheProblem) {
  const SilhouetteExtractor extractor{SilhouetteOptions{}};
  const cv::Mat image(48, 64, CV_8UC3, cv::Scalar::all(0));
  Silhouette out;
  const auto message = [&](const cv::Mat& a, const cv::Mat& b) -> std::string {
    try {
      extractor.Extract(a, b, &out);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no exception)";
  };
  const std::string size = message(image, cv::Mat(48, 63, CV_8UC3));
  EXPECT_NE(size.find("size"), std::string::npos) << size;
  EXPECT_NE(size.find("63x48"), std::string::npos) << size;
  const std::string grey = message(cv::Mat(48, 64, CV_8UC1), image);
  EXPECT_NE(grey.find("image"), std::string::npos) << grey;
  EXPECT_NE(grey.find("CV_8UC3"), std::string::npos) << grey;
  EXPECT_NE(grey.find("CV_8UC1"), std::string::npos) << grey;
  const std::string wide = message(image, cv::Mat(48, 64, CV_16UC3));
  EXPECT_NE(wide.find("background"), std::string::npos) << wide;
  EXPECT_NE(message(cv::Mat(), image).find("empty"), std::string::npos);
  EXPECT_THROW(extractor.Extract(image, image, nullptr), std::invalid_argument);
}

TEST(SilhouetteOptionsTest, DefaultsAreValid) { EXPECT_EQ(SilhouetteOptions{}.Validate(), ""); }

TEST(SilhouetteOptionsTest, ValidateNamesTheBadKey) {
  struct Case {
    const char* key;
    void (*spoil)(SilhouetteOptions&);
  };
  const Case cases[] = {
      {"threshold", [](SilhouetteOptions& o) { o.threshold = 0; }},
      {"threshold", [](SilhouetteOptions& o) { o.threshold = 255; }},
      {"dilation_radius", [](SilhouetteOptions& o) { o.dilation_radius = -1; }},
      {"dilation_radius", [](SilhouetteOptions& o) { o.dilation_radius = 11; }},
      {"shadow_max_angle_deg", [](SilhouetteOptions& o) { o.shadow_max_angle_deg = 90.0; }},
      {"shadow_max_angle_deg", [](SilhouetteOptions& o) { o.shadow_max_angle_deg = -1.0; }},
      {"shadow_min_brightness_ratio",
       [](SilhouetteOptions& o) { o.shadow_min_brightness_ratio = 1.5; }},
      {"min_component_area", [](SilhouetteOptions& o) { o.min_component_area = -1; }},
      {"tape.hue_deg",
       [](SilhouetteOptions& o) {
         o.tape.hue_deg = {335.0, 360.0};
       }},
      {"tape.hue_deg",
       [](SilhouetteOptions& o) {
         o.tape.hue_deg = {20.0, 20.0};
       }},
      {"tape.min_saturation", [](SilhouetteOptions& o) { o.tape.min_saturation = 0.0; }},
      {"tape.min_value", [](SilhouetteOptions& o) { o.tape.min_value = 256; }},
  };
  for (const Case& c : cases) {
    SilhouetteOptions options;
    c.spoil(options);
    const std::string error = options.Validate();
    EXPECT_EQ(error.rfind(std::string(c.key) + ": expected", 0), 0u) << error;
    EXPECT_THROW(SilhouetteExtractor{options}, std::invalid_argument) << c.key;
  }
}

}  // namespace
}  // namespace shapesense
