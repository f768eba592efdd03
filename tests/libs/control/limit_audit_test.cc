// The limit audit (limit_audit.h): it never flags what the real safety gate
// lets through, and it flags each kind of violation (range or tension, rate,
// malformed) on commands built to break exactly one limit.
#include "libs/control/limit_audit.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>

#include "libs/control/safety_gate.h"
#include "tests/libs/mechanics/test_models.h"

namespace shapesense {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

class LimitAuditTest : public ::testing::Test {
 protected:
  LimitAuditTest() : model_(testing::CatheterOptions()), envelope_(model_, limits_) {}

  // Well inside the envelope: every tension 1 N above the minimum, bending nothing.
  Eigen::VectorXd Base() const {
    Eigen::VectorXd base =
        envelope_.WithLeastTension(envelope_.RestingCommand(), limits_.min_tension + 1.0);
    EXPECT_EQ(envelope_.Check(base), "");
    return base;
  }

  // `step` mm on the tendon that moves most, along the pretension direction
  // (raises every tension, bends nothing): the rate is the only limit in play.
  Eigen::VectorXd Stepped(const Eigen::VectorXd& from, double step) const {
    const Eigen::VectorXd& direction = envelope_.pretension_displacements();
    Eigen::VectorXd to = from + direction * (step / direction.cwiseAbs().maxCoeff());
    EXPECT_EQ(envelope_.Check(to), "");
    return to;
  }

  SafetyLimits limits_;
  TendonModel model_;
  SafetyEnvelope envelope_;
};

TEST_F(LimitAuditTest, NeverFlagsWhatTheSafetyGateLetsThrough) {
  std::mt19937_64 rng(41);
  std::uniform_int_distribution<int> kind(0, 9);
  std::uniform_int_distribution<int64_t> period_us(1000, 30000);
  std::uniform_real_distribution<double> wide(-10.0, 10.0), near(-0.2, 0.2);
  SafetyGate gate(model_, limits_, WatchdogOptions{}, envelope_.RestingCommand());
  LimitAudit audit(envelope_);
  int64_t utime = 1'000'000;
  audit.Check(gate.command(), utime);
  const int64_t start = utime;
  double last_time = 0.0;
  constexpr int kSteps = 400;
  for (int step = 0; step < kSteps; ++step) {
    const int k = kind(rng);
    // Now and then a late step (capped at max_step_period by both).
    utime += k == 0 ? 400'000 : period_us(rng);
    // dt as the controller service takes it: a difference of times since start.
    const double time = static_cast<double>(utime - start) * 1e-6;
    const double dt = time - last_time;
    last_time = time;
    Eigen::VectorXd proposal(model_.num_tendons());
    for (int i = 0; i < proposal.size(); ++i) {
      proposal(i) = k < 5 ? wide(rng) : gate.command()(i) + near(rng);
    }
    if (k == 9) proposal(1) = kNaN;  // held by the gate
    audit.Check(gate.Apply(proposal, dt, 0.05, false).command, utime);
  }
  EXPECT_EQ(audit.commands(), kSteps + 1);
  EXPECT_EQ(audit.violations().total(), 0) << audit.first_violation();
  EXPECT_EQ(audit.first_violation(), "");
}

TEST_F(LimitAuditTest, FlagsACommandAboveItsRangeAndNamesIt) {
  LimitAudit audit(envelope_);
  Eigen::VectorXd command = Base();
  command(0) = envelope_.high()(0) + 0.5;
  audit.Check(command, 1'000'000);
  EXPECT_EQ(audit.violations().range_or_tension, 1);
  EXPECT_EQ(audit.violations().total(), 1);
  EXPECT_THAT(audit.first_violation(), StartsWith("command 1: tendon 0:"));
  EXPECT_THAT(audit.first_violation(), HasSubstr("outside its range"));
}

TEST_F(LimitAuditTest, FlagsATensionBelowTheMinimum) {
  LimitAudit audit(envelope_);
  const Eigen::VectorXd slack =
      envelope_.WithLeastTension(envelope_.RestingCommand(), limits_.min_tension - 0.1);
  audit.Check(slack, 1'000'000);
  EXPECT_EQ(audit.violations().range_or_tension, 1);
  EXPECT_THAT(audit.first_violation(), HasSubstr("below the minimum"));
}

TEST_F(LimitAuditTest, KeepsTheFirstViolationAndCountsEveryOne) {
  LimitAudit audit(envelope_);
  const Eigen::VectorXd base = Base();
  audit.Check(base, 1'000'000);
  Eigen::VectorXd high = base;
  high(0) = envelope_.high()(0) + 0.5;
  audit.Check(high, 2'000'000);  // out of range, and too far from `base`
  audit.Check(Eigen::VectorXd::Zero(2), 3'000'000);
  EXPECT_EQ(audit.commands(), 3);
  EXPECT_EQ(audit.violations().range_or_tension, 1);
  EXPECT_EQ(audit.violations().rate, 1);
  EXPECT_EQ(audit.violations().malformed, 1);
  EXPECT_EQ(audit.violations().total(), 3);
  EXPECT_THAT(audit.first_violation(), StartsWith("command 2: tendon 0:"));
}

TEST_F(LimitAuditTest, FlagsAStepFasterThanMaxRateButNotOneAtIt) {
  const int64_t period_us = 10'000;
  const double allowed = limits_.max_rate * 0.01;
  ASSERT_LT(0.01, limits_.max_step_period);
  {
    LimitAudit audit(envelope_);
    const Eigen::VectorXd base = Base();
    audit.Check(base, 1'000'000);
    audit.Check(Stepped(base, allowed), 1'000'000 + period_us);
    EXPECT_EQ(audit.violations().total(), 0) << audit.first_violation();
  }
  {
    LimitAudit audit(envelope_);
    const Eigen::VectorXd base = Base();
    audit.Check(base, 1'000'000);
    audit.Check(Stepped(base, allowed * 1.001), 1'000'000 + period_us);
    EXPECT_EQ(audit.violations().rate, 1);
    EXPECT_EQ(audit.violations().total(), 1);
    EXPECT_THAT(audit.first_violation(), StartsWith("command 2: a tendon moved"));
  }
}

TEST_F(LimitAuditTest, ALongGapAllowsNoMoreThanMaxRateTimesMaxStepPeriod) {
  // 1 s between commands: max_rate * 1 s would allow 2 mm; the cap is 0.1 mm.
  const int64_t gap_us = 1'000'000;
  const double capped = limits_.max_rate * limits_.max_step_period;
  ASSERT_LT(capped * 2.0, limits_.max_rate * 1.0);
  const Eigen::VectorXd base = Base();
  for (const double factor : {0.5, 1.0, 1.001, 2.0, 5.0}) {
    LimitAudit audit(envelope_);
    audit.Check(base, 1'000'000);
    audit.Check(Stepped(base, capped * factor), 1'000'000 + gap_us);
    EXPECT_EQ(audit.violations().rate, factor > 1.0 ? 1 : 0) << factor;
  }
}

// Commands lost on the way to the audit (a link down on a rig of several
// hosts) each had a step: across a gap of k step numbers the command may
// have moved k capped steps, and no more.
TEST_F(LimitAuditTest, CommandsItMissedEachHadTheirStep) {
  const double capped = limits_.max_rate * limits_.max_step_period;
  const Eigen::VectorXd base = Base();
  for (const double factor : {2.9, 3.1}) {
    LimitAudit audit(envelope_);
    audit.Check(base, 1'000'000, 10);
    audit.Check(Stepped(base, capped * factor), 3'000'000, 13);  // 11 and 12 missed
    EXPECT_EQ(audit.violations().rate, factor > 3.0 ? 1 : 0) << factor;
    EXPECT_EQ(audit.missed(), 2);
  }
  // Without step numbers, the one capped step.
  LimitAudit audit(envelope_);
  audit.Check(base, 1'000'000);
  audit.Check(Stepped(base, capped * 2.9), 3'000'000);
  EXPECT_EQ(audit.violations().rate, 1);
  EXPECT_EQ(audit.missed(), 0);
}

TEST_F(LimitAuditTest, WrongSizeAndNotFiniteAreMalformed) {
  LimitAudit audit(envelope_);
  const Eigen::VectorXd base = Base();
  audit.Check(Eigen::VectorXd(base.head(base.size() - 1)), 1'000'000);
  Eigen::VectorXd longer(base.size() + 1);
  longer << base, 0.0;
  audit.Check(longer, 1'010'000);
  Eigen::VectorXd nan = base;
  nan(2) = kNaN;
  audit.Check(nan, 1'020'000);
  Eigen::VectorXd inf = base;
  inf(0) = std::numeric_limits<double>::infinity();
  audit.Check(inf, 1'030'000);
  EXPECT_EQ(audit.commands(), 4);
  EXPECT_EQ(audit.violations().malformed, 4);
  EXPECT_EQ(audit.violations().total(), 4);
  EXPECT_THAT(audit.first_violation(), StartsWith("command 1: "));
}

TEST_F(LimitAuditTest, AJumpBetweenTwoCommandsIsARateViolation) {
  const Eigen::VectorXd base = Base();
  const Eigen::VectorXd far = Stepped(base, 1.0);  // 10x what any step may move
  LimitAudit audit(envelope_);
  audit.Check(base, 1'000'000);
  audit.Check(far, 1'010'000);
  audit.Check(Stepped(far, 0.01), 1'020'000);  // checked against `far`: within the rate
  EXPECT_EQ(audit.violations().rate, 1);
}

TEST_F(LimitAuditTest, CountsEveryCommand) {
  LimitAudit audit(envelope_);
  EXPECT_EQ(audit.commands(), 0);
  EXPECT_EQ(audit.violations().total(), 0);
  Eigen::VectorXd command = Base();
  for (int k = 1; k <= 25; ++k) {
    audit.Check(k % 5 == 0 ? Eigen::VectorXd::Zero(1) : command, 1'000'000 + k * 10'000);
    if (k % 5 != 0) command = Stepped(command, 0.001);
    EXPECT_EQ(audit.commands(), k);
  }
  EXPECT_EQ(audit.violations().malformed, 5);
  EXPECT_EQ(audit.violations().total(), 5);
}

}  // namespace
}  // namespace shapesense
