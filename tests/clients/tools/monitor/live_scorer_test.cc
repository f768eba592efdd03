#include "clients/tools/monitor/live_scorer.h"

#include <gtest/gtest.h>

namespace shapesense {
namespace {

shape_t StraightShape(int64_t trigger_utime, double offset_x, bool valid = true) {
  shape_t shape{};
  shape.trigger_utime = trigger_utime;
  shape.valid = valid;
  for (int i = 0; i <= 100; ++i)
    shape.centerline.push_back({offset_x, 0.0, static_cast<double>(i)});
  shape.num_points = static_cast<int32_t>(shape.centerline.size());
  shape.tip[0] = offset_x;
  shape.tip[2] = 100.0;
  return shape;
}

TEST(LiveScorerTest, PairsShapesWithTheTruthOfTheSameTrigger) {
  LiveScorer scorer(/*match_tolerance_us=*/5000);
  for (int i = 0; i < 10; ++i) scorer.AddTruth(StraightShape(1'000'000 + i * 33'333, 0.0));
  // Shapes arrive with trigger times a little off the rig's (separate processes),
  // measured 0.4 mm off the truth.
  for (int i = 0; i < 10; ++i) {
    shape_t shape = StraightShape(1'000'000 + i * 33'333 + 900, 0.4);
    shape.stage_times.push_back({"carving", 300, 0});
    shape.stage_times.push_back({"shape", 700 + i, 0});
    scorer.AddShape(shape, shape.trigger_utime + 2000);
  }
  const LiveScorer::Report report = scorer.Finish(/*end_utime=*/5'000'000);
  EXPECT_EQ(report.truths, 10);
  EXPECT_EQ(report.matched, 10);
  EXPECT_EQ(report.unmatched_truths, 0);
  EXPECT_NEAR(report.centerline_rms_mean, 0.4, 1e-9);
  EXPECT_NEAR(report.tip_error_max, 0.4, 1e-9);
  EXPECT_NEAR(report.stage_ms.at("carving").p50, 0.3, 1e-9);
  EXPECT_NEAR(report.stage_ms.at("shape").max, 0.709, 1e-9);
  EXPECT_NEAR(report.trigger_to_shape_ms.p99, 2.0, 1e-9);
}

// From another host, the trigger time is another clock: the shape's age,
// summed on each host's own clock, is its latency, whatever the offset.
TEST(LiveScorerTest, AShapesAgeIsItsLatencyWhateverTheClocks) {
  LiveScorer scorer(5000);
  shape_t shape = StraightShape(1'000'000, 0.0);
  shape.header.data_age_us = 31'000;
  scorer.AddShape(shape, 1'000'000 - 500'000);  // received on a clock 0.5 s behind
  EXPECT_NEAR(scorer.Finish(2'000'000).trigger_to_shape_ms.p50, 31.0, 1e-9);
}

TEST(LiveScorerTest, CountsLostFrameSetsButNotThoseStillInFlight) {
  LiveScorer scorer(5000);
  for (int64_t i = 0; i < 10; ++i) scorer.AddTruth(StraightShape(i * 100'000, 0.0));
  for (const int64_t i : {0, 1, 2, 5, 6})
    scorer.AddShape(StraightShape(i * 100'000, 0.1), i * 100'000 + 1000);
  scorer.AddShape(StraightShape(int64_t{3} * 100'000, 0.1, /*valid=*/false), 0);
  // The run ended at 1.0 s: truths at 0.6 s and later are within the grace period.
  const LiveScorer::Report report = scorer.Finish(1'000'000, 450'000);
  EXPECT_EQ(report.matched, 5);
  EXPECT_EQ(report.valid_shapes, 5);
  EXPECT_EQ(report.shapes, 6);
  EXPECT_EQ(report.unmatched_truths, 2);  // 3 (invalid) and 4 (never measured)
}

TEST(LiveScorerTest, AShapeFarFromAnyTruthIsNotPaired) {
  LiveScorer scorer(5000);
  scorer.AddTruth(StraightShape(0, 0.0));
  scorer.AddShape(StraightShape(50'000, 3.0), 51'000);
  EXPECT_EQ(scorer.Finish(10'000'000).matched, 0);
}

}  // namespace
}  // namespace shapesense
