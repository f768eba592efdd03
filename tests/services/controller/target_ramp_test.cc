// A streamed move's target over time (TargetRamp::At): `from` until start
// (also for a step, duration 0, set to start later), linear over the
// duration, then `to`.
#include <gtest/gtest.h>

#include <limits>

#include "services/controller/controller_inputs.h"

namespace shapesense {
namespace {

TargetRamp Ramp(double start, double duration) {
  TargetRamp ramp;
  ramp.from = Configuration(0.001, -0.002, 0.0005, 0.003);
  ramp.to = Configuration(-0.003, 0.004, 0.0015, 0.001);
  ramp.start = start;
  ramp.duration = duration;
  return ramp;
}

TEST(TargetRampTest, AStepThatStartsLaterHoldsFromUntilItsStart) {
  const TargetRamp ramp = Ramp(5.0, 0.0);
  for (const double time : {0.0, 4.0, 4.999999}) {
    EXPECT_EQ(ramp.At(time), ramp.from) << time;
  }
  for (const double time : {5.0, 5.000001, 6.0, 100.0}) {
    EXPECT_EQ(ramp.At(time), ramp.to) << time;
  }
}

TEST(TargetRampTest, IsLinearOverItsDuration) {
  const TargetRamp ramp = Ramp(5.0, 2.0);
  EXPECT_EQ(ramp.At(5.0), ramp.from);
  EXPECT_LT((ramp.At(6.0) - 0.5 * (ramp.from + ramp.to)).norm(), 1e-15);
  EXPECT_LT((ramp.At(5.5) - (0.75 * ramp.from + 0.25 * ramp.to)).norm(), 1e-15);
  EXPECT_EQ(ramp.At(7.0), ramp.to);
  EXPECT_EQ(ramp.At(9.0), ramp.to);
  // Every point between lies on the segment, at the fraction of time passed.
  for (int k = 0; k <= 100; ++k) {
    const double fraction = k / 100.0;
    const Configuration expected = ramp.from + fraction * (ramp.to - ramp.from);
    EXPECT_LT((ramp.At(5.0 + 2.0 * fraction) - expected).norm(), 1e-12) << fraction;
  }
}

TEST(TargetRampTest, HoldsFromBeforeTheStartOfARamp) {
  const TargetRamp ramp = Ramp(5.0, 2.0);
  for (const double time : {-1.0, 0.0, 4.9}) {
    EXPECT_EQ(ramp.At(time), ramp.from) << time;
  }
}

TEST(TargetRampTest, ANaNDurationIsAStep) {
  const TargetRamp ramp = Ramp(5.0, std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(ramp.At(4.0), ramp.from);
  EXPECT_EQ(ramp.At(5.0), ramp.to);
  EXPECT_EQ(ramp.At(6.0), ramp.to);
  EXPECT_TRUE(ramp.At(5.5).allFinite());
}

}  // namespace
}  // namespace shapesense
