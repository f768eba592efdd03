#include "libs/centerline/silhouette_edges.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "libs/silhouette/compact_silhouette.h"
#include "tests/libs/centerline/tube_fixture.h"
#include "tests/libs/silhouette/synthetic_frame.h"

namespace shapesense {
namespace {

using testing::Uniform;

// The area of the unit pixel centred at c on the side normal·x < offset of
// a straight edge (normal a unit vector): the integral of the pixel's
// projection onto the normal, a trapezoid, up to the edge.
double Coverage(const Vec2& normal, double offset, const Vec2& c) {
  const double s = offset - normal.dot(c);
  const double a = std::max(std::abs(normal.x()), std::abs(normal.y()));
  const double b = std::min(std::abs(normal.x()), std::abs(normal.y()));
  const double h = 0.5 * (a + b);
  const double k = 0.5 * (a - b);
  if (s <= -h) return 0.0;
  if (s >= h) return 1.0;
  if (b < 1e-12) return std::clamp(s / a + 0.5, 0.0, 1.0);
  if (s < -k) return (s + h) * (s + h) / (2.0 * a * b);
  if (s <= k) return b / (2.0 * a) + (s + k) / a;
  return 1.0 - (h - s) * (h - s) / (2.0 * a * b);
}

// A body on the side normal·x < offset of a straight edge, anti-aliased by
// its exact coverage of each pixel, over a backdrop.
Silhouette EdgeImage(const Vec2& normal, double offset, double body, double backdrop,
                     double noise_sigma, std::mt19937& rng) {
  Silhouette s;
  s.mask = cv::Mat::zeros(120, 160, CV_8U);
  s.labels = cv::Mat::zeros(120, 160, CV_8U);
  s.difference = cv::Mat::zeros(120, 160, CV_8U);
  std::normal_distribution<double> noise(0.0, noise_sigma);
  for (int y = 0; y < s.mask.rows; ++y) {
    for (int x = 0; x < s.mask.cols; ++x) {
      const double coverage = Coverage(normal, offset, Vec2(x, y));
      const double value = backdrop + coverage * (body - backdrop) + noise(rng);
      s.difference.at<uint8_t>(y, x) =
          static_cast<uint8_t>(std::clamp(std::lround(value), 0L, 255L));
      if (coverage > 0.3) s.mask.at<uint8_t>(y, x) = 255;
    }
  }
  s.labels.setTo(kLabelBody, s.mask);
  return s;
}

struct Case {
  Vec2 normal;
  double offset;
  Vec2 start;
  Vec2 direction;
};

Case RandomCase(std::mt19937& rng) {
  const double angle = Uniform(rng, 0.0, 2.0 * 3.14159);
  Case c;
  c.normal = Vec2(std::cos(angle), std::sin(angle));
  c.start = Vec2(Uniform(rng, 60, 100), Uniform(rng, 45, 75));
  // The walk leaves at up to 20° from the edge's normal (it goes across
  // the projected axis, which the outline nearly follows).
  const double tilt = Uniform(rng, -0.35, 0.35);
  c.direction = Eigen::Rotation2Dd(tilt) * c.normal;
  c.offset = c.normal.dot(c.start) + Uniform(rng, 1.0, 8.0);
  return c;
}

double TrueDistance(const Case& c) {
  return (c.offset - c.normal.dot(c.start)) / c.normal.dot(c.direction);
}

// Error of the edge across itself, px, over random edges and walks.
struct ErrorStats {
  double mean = 0.0;
  double rms = 0.0;
  double worst = 0.0;
};

ErrorStats EdgeErrors(double backdrop_low, double backdrop_high, double noise, uint32_t seed) {
  std::mt19937 rng(seed);
  const int trials = 60;
  ErrorStats stats;
  for (int trial = 0; trial < trials; ++trial) {
    const Case c = RandomCase(rng);
    const Silhouette s =
        EdgeImage(c.normal, c.offset, 120.0, Uniform(rng, backdrop_low, backdrop_high), noise, rng);
    const std::optional<double> d = FindEdgeAlong(s, c.start, c.direction, 20);
    EXPECT_TRUE(d.has_value()) << "trial " << trial;
    if (!d) continue;
    const double error = (*d - TrueDistance(c)) * c.normal.dot(c.direction);
    stats.mean += error / trials;
    stats.rms += error * error / trials;
    stats.worst = std::max(stats.worst, std::abs(error));
  }
  stats.rms = std::sqrt(stats.rms);
  return stats;
}

// Bilinear sampling of an anti-aliased edge errs by up to about a tenth of
// a pixel depending on where the edge falls between pixel centres, but not
// on average.
TEST(FindEdgeAlongTest, PlacesAnAntiAliasedEdgeToAFractionOfAPixel) {
  const ErrorStats stats = EdgeErrors(0.0, 4.0, 0.0, 12);
  EXPECT_LT(std::abs(stats.mean), 0.03);
  EXPECT_LT(stats.rms, 0.07);
  EXPECT_LT(stats.worst, 0.15);
}

TEST(FindEdgeAlongTest, IsUnbiasedByNoiseAndByAShadowedBackdrop) {
  // A shadow lifts the backdrop's difference to 40-70 grey levels.
  const ErrorStats stats = EdgeErrors(40.0, 70.0, 2.0, 13);
  EXPECT_LT(std::abs(stats.mean), 0.03);
  EXPECT_LT(stats.rms, 0.1);
}

TEST(FindEdgeAlongTest, GivesUpWhereTheEdgeCannotBeMeasured) {
  std::mt19937 rng(14);
  const Vec2 normal(1.0, 0.0);
  const Silhouette s = EdgeImage(normal, 80.0, 120.0, 0.0, 0.0, rng);
  // Found within reach; not when the body goes on past max_steps (another
  // part of the tube), nor from outside the mask, nor off the image.
  EXPECT_TRUE(FindEdgeAlong(s, Vec2(70, 60), normal, 15).has_value());
  EXPECT_FALSE(FindEdgeAlong(s, Vec2(60, 60), normal, 15).has_value());
  EXPECT_FALSE(FindEdgeAlong(s, Vec2(90, 60), normal, 15).has_value());
  EXPECT_FALSE(FindEdgeAlong(s, Vec2(70, 60), -normal, 80).has_value());
  EXPECT_FALSE(FindEdgeAlong(s, Vec2(-3, 60), normal, 15).has_value());
  // Too little contrast to place an edge.
  const Silhouette faint = EdgeImage(normal, 80.0, 5.0, 0.0, 0.0, rng);
  Silhouette masked = faint;
  masked.mask = s.mask;
  EXPECT_FALSE(FindEdgeAlong(masked, Vec2(70, 60), normal, 15).has_value());
}

// What the shape service gets (libs/silhouette/compact_silhouette.h) must
// place every edge where the full silhouette does: walks from random pixels
// of the mask in random directions, on frames with holes, blobs, shadows and
// a tube leaving the image.
TEST(FindEdgeAlongTest, FindsTheSameEdgesInACompactedSilhouette) {
  std::mt19937 rng(15);
  int found = 0;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    testing::FrameSpec spec;
    spec.seed = seed;
    spec.second_tube = seed == 3;
    const testing::SyntheticFrame frame = testing::MakeFrame(spec);
    Silhouette original;
    SilhouetteExtractor(SilhouetteOptions{}).Extract(frame.image, frame.background, &original);
    CompactSilhouette compact;
    CompactScratch scratch;
    Compact(original, &compact, &scratch);
    Silhouette expanded;
    Expand(compact, &expanded);
    for (int walk = 0; walk < 4000; ++walk) {
      const RowRun& run = original.runs[rng() % original.runs.size()];
      const Vec2 start(Uniform(rng, run.x0, run.x1 - 1), run.y + Uniform(rng, -0.4, 0.4));
      const double angle = Uniform(rng, 0.0, 2.0 * M_PI);
      const Vec2 direction(std::cos(angle), std::sin(angle));
      const std::optional<double> a = FindEdgeAlong(original, start, direction, 40);
      ASSERT_EQ(a, FindEdgeAlong(expanded, start, direction, 40))
          << "seed " << seed << " from (" << start.transpose() << ") along ("
          << direction.transpose() << ")";
      found += a.has_value() ? 1 : 0;
    }
  }
  EXPECT_GT(found, 3000);  // most walks reach an edge: the test is not vacuous
}

TEST(CoverageTest, MatchesSupersampling) {
  std::mt19937 rng(15);
  for (int trial = 0; trial < 200; ++trial) {
    const double angle = Uniform(rng, 0.0, 6.3);
    const Vec2 normal(std::cos(angle), std::sin(angle));
    const double offset = Uniform(rng, -1.0, 1.0);
    int inside = 0;
    for (int j = 0; j < 64; ++j) {
      for (int i = 0; i < 64; ++i) {
        inside += normal.dot(Vec2(-0.5 + (i + 0.5) / 64.0, -0.5 + (j + 0.5) / 64.0)) < offset;
      }
    }
    EXPECT_NEAR(Coverage(normal, offset, Vec2::Zero()), inside / 4096.0, 0.01);
  }
}

TEST(SampleBilinearTest, InterpolatesBetweenPixelCentres) {
  cv::Mat image = (cv::Mat_<uint8_t>(2, 2) << 0, 100, 50, 150);
  EXPECT_DOUBLE_EQ(SampleBilinear(image, Vec2(0, 0)), 0.0);
  EXPECT_DOUBLE_EQ(SampleBilinear(image, Vec2(0.5, 0)), 50.0);
  EXPECT_DOUBLE_EQ(SampleBilinear(image, Vec2(0, 0.5)), 25.0);
  // Top row 25, bottom row 75 at x = 0.25.
  EXPECT_DOUBLE_EQ(SampleBilinear(image, Vec2(0.25, 0.75)), 62.5);
}

}  // namespace
}  // namespace shapesense
