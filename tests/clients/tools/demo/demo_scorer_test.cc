// The demo's scoring on synthetic truths and shapes: a shape equal to its
// frame-set's truth scores zero, a shape moved by d has its tip and tapes d
// away and its centreline at most d, a shape is paired only within the
// tolerance, and invalid shapes are counted apart; the truth message reads
// back as the ground truth it came from.
#include "clients/tools/demo/demo_scorer.h"

#include <gtest/gtest.h>

#include <random>

#include "libs/sim/scene_generators.h"
#include "runtime/lcm/shape_message.h"

namespace shapesense {
namespace {

constexpr int64_t kTolerance = 8000;  // µs
constexpr int64_t kPeriod = 33333;    // µs between frame-sets

// A random arc, with tapes at three of its points, as a shape message.
shape_t RandomArcShape(std::mt19937& random, int64_t seq, int64_t trigger_utime) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double plane = 6.283 * unit(random);
  const Polyline centerline =
      ArcCenterline(Vec3(0, 0, 0), Vec3::UnitZ(), Vec3(std::cos(plane), std::sin(plane), 0), 10.0,
                    140.0, 2.5 * unit(random), 1.0);
  ShapeEstimate estimate;
  estimate.valid = true;
  estimate.centerline = centerline;
  estimate.arc_length.assign(centerline.size(), 0.0);
  estimate.curvature.assign(centerline.size(), 0.0);
  for (const double f : {0.25, 0.55, 0.85}) {
    estimate.markers.push_back(centerline[static_cast<size_t>(f * (centerline.size() - 1))]);
    estimate.marker_arc_length.push_back(f * 150.0);
  }
  estimate.tip = centerline.back();
  estimate.length = 150.0;
  shape_t message = ShapeToMessage(estimate);
  message.trigger_seq = seq;
  message.trigger_utime = trigger_utime;
  return message;
}

shape_t Moved(shape_t shape, const Vec3& d) {
  for (auto* points : {&shape.centerline, &shape.markers}) {
    for (std::vector<double>& p : *points) {
      for (int k = 0; k < 3; ++k) p[k] += d[k];
    }
  }
  for (int k = 0; k < 3; ++k) shape.tip[k] += d[k];
  return shape;
}

TEST(DemoScorerTest, TheTruthMessageReadsBackAsItsGroundTruth) {
  std::mt19937 random(1);
  const shape_t truth = RandomArcShape(random, 0, 0);
  const GroundTruth read = GroundTruthFromMessage(truth);
  ShapeEstimate estimate;
  ASSERT_EQ(ShapeFromMessage(truth, &estimate), "");
  const ShapeError error = CompareShape(estimate, read);
  EXPECT_EQ(error.centerline_rms, 0.0);
  EXPECT_EQ(error.tip, 0.0);
  EXPECT_EQ(error.marker_max, 0.0);
  EXPECT_EQ(error.markers_found, 3);
  EXPECT_EQ(read.length, truth.length);
}

TEST(DemoScorerTest, AShapeMovedByDIsScoredAtD) {
  std::mt19937 random(2);
  std::uniform_real_distribution<double> offset(-1.0, 1.0);
  DemoScorer scorer(kTolerance);
  const int64_t start = 1'700'000'000'000'000;
  double largest = 0.0;
  for (int64_t seq = 0; seq < 40; ++seq) {
    const int64_t trigger = start + seq * kPeriod;
    const shape_t truth = RandomArcShape(random, seq + 1000, trigger + 3000);  // its own count
    const Vec3 d(offset(random), offset(random), offset(random));
    largest = std::max(largest, d.norm());
    shape_t shape = Moved(truth, d);
    shape.trigger_seq = seq;
    shape.trigger_utime = trigger;
    scorer.AddTruth(truth);
    scorer.AddShape(shape, trigger + 40000);
  }
  const DemoScore score = scorer.Finish(start + 41 * kPeriod);
  EXPECT_EQ(score.live.matched, 40);
  EXPECT_EQ(score.errors.frames, 40);
  EXPECT_NEAR(score.errors.max.tip, largest, 1e-9);
  EXPECT_NEAR(score.live.tip_error_max, largest, 1e-9);
  EXPECT_NEAR(score.errors.max.marker_max, largest, 1e-9);
  EXPECT_LE(score.live.centerline_rms_max, largest + 1e-9);
  EXPECT_EQ(score.errors.mean.markers_found, 120);
  EXPECT_EQ(scorer.shapes_by_seq().size(), 40u);
}

TEST(DemoScorerTest, PairedOnlyWithinTheToleranceAndInvalidShapesApart) {
  std::mt19937 random(3);
  DemoScorer scorer(kTolerance);
  const int64_t start = 1'700'000'000'000'000;
  int paired = 0;
  for (int64_t seq = 0; seq < 30; ++seq) {
    const int64_t trigger = start + seq * kPeriod;
    const int64_t gap = std::uniform_int_distribution<int64_t>(-15000, 15000)(random);
    scorer.AddTruth(RandomArcShape(random, seq, trigger + gap));
    shape_t shape = RandomArcShape(random, seq, trigger);
    shape.valid = seq % 5 != 0;
    paired += shape.valid && std::llabs(gap) <= kTolerance;
    scorer.AddShape(shape, trigger + 50000);
  }
  const DemoScore score = scorer.Finish(start + 31 * kPeriod);
  EXPECT_EQ(score.live.matched, paired);
  EXPECT_EQ(score.errors.frames - score.errors.failed, paired);
  EXPECT_EQ(score.errors.failed, 6);
  EXPECT_EQ(score.live.valid_shapes, 24);
}

TEST(DemoScorerTest, RemembersWhichServicesReported) {
  DemoScorer scorer;
  service_status_t status{};
  status.service = "carving";
  scorer.AddStatus(status);
  EXPECT_TRUE(scorer.StatusSeen("carving"));
  EXPECT_FALSE(scorer.StatusSeen("shape"));
}

}  // namespace
}  // namespace shapesense
