#include "libs/control/safety_gate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include "tests/libs/mechanics/test_models.h"

namespace shapesense {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Limits drawn around a layout's own resting pose, so that the safe set is
// never empty: ranges that hold the resting command with room of 1-10 mm on
// either side, rates of 0.5-20 mm/s, minimum tensions of 0-2 N.
SafetyLimits RandomLimits(const TendonModel& model, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> room(1.0, 10.0), rate(0.5, 20.0), tension(0.0, 2.0);
  SafetyLimits limits;
  limits.min_tension = tension(rng);
  limits.max_rate = rate(rng);
  const Eigen::VectorXd resting =
      model.InverseWithMinimumTension(Configuration::Zero(), limits.min_tension).displacements;
  for (int i = 0; i < model.num_tendons(); ++i) {
    limits.tendon_ranges.push_back({resting(i) - room(rng), resting(i) + room(rng)});
  }
  return limits;
}

// Proposals of every kind: anywhere in a wide box, close to the last
// command, slack (all pushed), and now and then not finite or the wrong size.
Eigen::VectorXd RandomProposal(const Eigen::VectorXd& previous, std::mt19937_64& rng) {
  const int n = static_cast<int>(previous.size());
  std::uniform_int_distribution<int> kind(0, 19);
  std::uniform_real_distribution<double> wide(-25.0, 25.0), near(-0.3, 0.3);
  Eigen::VectorXd proposal(n);
  const int k = kind(rng);
  for (int i = 0; i < n; ++i) proposal(i) = k < 8 ? wide(rng) : previous(i) + near(rng);
  if (k == 16) proposal(0) = kNaN;
  if (k == 17) proposal(n - 1) = kInf;
  if (k == 18) proposal = Eigen::VectorXd::Zero(n + 1);
  if (k == 19) proposal = -Eigen::VectorXd::Ones(n) * 3.0;  // everything slack
  return proposal;
}

// Periods, sensing ages and e-stop: mostly nominal, sometimes not.
GateInput RandomConditions(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> kind(0, 29);
  std::uniform_real_distribution<double> period(0.001, 0.03), fresh(0.0, 0.19);
  GateInput input;
  input.dt = period(rng);
  input.sensing_age = fresh(rng);
  switch (kind(rng)) {
    case 0:
      input.emergency_stop = true;
      break;
    case 1:
      input.sensing_age = 0.5;
      break;  // stale
    case 2:
      input.sensing_age = 3.0;
      break;  // lost
    case 3:
      input.sensing_age = kNaN;
      break;  // lost
    case 4:
      input.dt = 0.0;
      break;
    case 5:
      input.dt = -0.01;
      break;
    case 6:
      input.dt = 5.0;
      break;  // a late step: capped at max_step_period
    case 7:
      input.dt = kNaN;
      break;
    default:
      break;
  }
  return input;
}

double MaxStep(const SafetyLimits& limits, double dt) {
  return limits.max_rate * std::min(dt, limits.max_step_period);
}

bool ShouldHold(const GateInput& input, int n) {
  return input.proposal.size() != n || !input.proposal.allFinite() || input.emergency_stop ||
         !(input.sensing_age < 0.2) || !(input.dt > 0.0) || !std::isfinite(input.dt);
}

// The gate's promises for one step from a safe previous command.
void ExpectSafeStep(const TendonModel& model, const SafetyEnvelope& envelope,
                    const GateInput& input, const GateResult& result) {
  const SafetyLimits& limits = envelope.limits();
  ASSERT_EQ(result.command.size(), model.num_tendons());
  ASSERT_TRUE(result.command.allFinite());
  EXPECT_GE((result.command - envelope.low()).minCoeff(), 0.0) << "below range";
  EXPECT_GE((envelope.high() - result.command).minCoeff(), 0.0) << "above range";
  EXPECT_GE(envelope.Tensions(result.command).minCoeff(), limits.min_tension);
  EXPECT_GE(model.Tensions(result.command).minCoeff(), limits.min_tension - 1e-9);
  if (ShouldHold(input, model.num_tendons())) {
    EXPECT_TRUE(result.held);
    EXPECT_EQ(result.command, input.previous) << "moved while it should hold";
  } else {
    const double step = (result.command - input.previous).cwiseAbs().maxCoeff();
    EXPECT_LE(step, MaxStep(limits, input.dt) * (1.0 + 1e-12) + 1e-12) << "too fast";
  }
}

TEST(SafetyGatePropertyTest, NoCommandEverLeavesTheBounds) {
  std::mt19937_64 rng(11);
  const WatchdogOptions watchdog;  // hold at 0.2 s, stop at 1 s
  int moved = 0, raised = 0, clamped = 0, rate_limited = 0;
  for (int layout = 0; layout < 40; ++layout) {
    const TendonModel model(testing::RandomOptions(rng));
    const SafetyEnvelope envelope(model, RandomLimits(model, rng));
    ASSERT_EQ(envelope.RestingCommand().size(), model.num_tendons());
    ASSERT_EQ(envelope.Check(envelope.RestingCommand()), "");
    Eigen::VectorXd previous = envelope.RestingCommand();
    for (int step = 0; step < 250; ++step) {
      GateInput input = RandomConditions(rng);
      input.previous = previous;
      input.proposal = RandomProposal(previous, rng);
      const GateResult result = GateCommand(envelope, watchdog, input);
      ExpectSafeStep(model, envelope, input, result);
      if (::testing::Test::HasFailure()) return;
      moved += result.command != previous;
      raised += result.has(kGateRaisedForTension);
      clamped += result.has(kGateClampedToRange);
      rate_limited += result.has(kGateRateLimited);
      previous = result.command;
    }
  }
  // The histories did exercise every branch.
  EXPECT_GT(moved, 2000);
  EXPECT_GT(raised, 100);
  EXPECT_GT(clamped, 500);
  EXPECT_GT(rate_limited, 1000);
}

TEST(SafetyGatePropertyTest, FromAnUnsafeCommandItOnlyHeals) {
  // A power-up with slack tendons or outside the range: no step takes a
  // tendon farther out of its range or lowers a tension already below the floor.
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> offset(-8.0, 8.0);
  const WatchdogOptions watchdog;
  for (int layout = 0; layout < 40; ++layout) {
    const TendonModel model(testing::RandomOptions(rng));
    const SafetyEnvelope envelope(model, RandomLimits(model, rng));
    const int n = model.num_tendons();
    Eigen::VectorXd previous = envelope.RestingCommand();
    for (int i = 0; i < n; ++i) previous(i) += offset(rng);
    for (int step = 0; step < 200; ++step) {
      GateInput input = RandomConditions(rng);
      input.previous = previous;
      input.proposal = RandomProposal(previous, rng);
      const Eigen::VectorXd out = GateCommand(envelope, watchdog, input).command;
      const Eigen::VectorXd before = envelope.Tensions(previous), after = envelope.Tensions(out);
      for (int i = 0; i < n; ++i) {
        const double was_out =
            std::max(envelope.low()(i) - previous(i), previous(i) - envelope.high()(i));
        const double is_out = std::max(envelope.low()(i) - out(i), out(i) - envelope.high()(i));
        EXPECT_LE(std::max(is_out, 0.0), std::max(was_out, 0.0)) << "tendon " << i;
        EXPECT_GE(after(i), std::min(before(i), envelope.limits().min_tension)) << "tendon " << i;
      }
      const double dt = std::isfinite(input.dt) && input.dt > 0.0 ? input.dt : 0.0;
      EXPECT_LE((out - previous).cwiseAbs().maxCoeff(),
                MaxStep(envelope.limits(), dt) * (1.0 + 1e-12) + 1e-12);
      if (::testing::Test::HasFailure()) return;
      previous = out;
    }
  }
}

TEST(SafetyGatePropertyTest, SafeSlowProposalsPassUnchanged) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const WatchdogOptions watchdog;
  std::unique_ptr<TendonModel> model;
  std::unique_ptr<SafetyEnvelope> envelope;
  int passed = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    // A new layout every 50 proposals: building an envelope is the dear part.
    if (trial % 50 == 0) {
      model = std::make_unique<TendonModel>(testing::RandomOptions(rng));
      envelope = std::make_unique<SafetyEnvelope>(*model, RandomLimits(*model, rng));
    }
    GateInput input;
    // From half a newton above the floor, pulling every tendon by less than
    // one step mostly stays safe (pulling one tendon slackens others a little).
    double unused = 0.0;
    input.previous = envelope->RaiseTensions(envelope->RestingCommand(),
                                             envelope->limits().min_tension + 0.5, &unused);
    input.dt = 0.01;
    Eigen::VectorXd pull(model->num_tendons());
    for (int i = 0; i < pull.size(); ++i) pull(i) = std::abs(unit(rng));
    input.proposal = input.previous + MaxStep(envelope->limits(), input.dt) * 0.99 * pull;
    if (!envelope->Check(input.proposal).empty()) continue;
    const GateResult result = GateCommand(*envelope, watchdog, input);
    EXPECT_EQ(result.reasons, 0u) << DescribeGateReasons(result.reasons);
    EXPECT_EQ(result.command, input.proposal);
    ++passed;
  }
  EXPECT_GT(passed, 500);
}

TEST(SafetyGatePropertyTest, ItNeverStallsShortOfASafeProposal) {
  // Repeating one safe proposal reaches it in as many steps as the rate
  // limit needs, and the tension floor never blocks the way there.
  std::mt19937_64 rng(14);
  const WatchdogOptions watchdog;
  for (int trial = 0; trial < 60; ++trial) {
    const TendonModel model(testing::RandomOptions(rng));
    const SafetyEnvelope envelope(model, RandomLimits(model, rng));
    std::uniform_real_distribution<double> bend(-1.5, 1.5);
    Configuration q = Configuration::Zero();
    q.head<2>() << bend(rng) / model.lengths().distal, bend(rng) / model.lengths().distal;
    const Eigen::VectorXd goal =
        model.InverseWithMinimumTension(q, envelope.limits().min_tension + 1e-6).displacements;
    if (!envelope.Check(goal).empty()) continue;
    GateInput input;
    input.previous = envelope.RestingCommand();
    input.proposal = goal;
    input.dt = 0.01;
    const double distance = (goal - input.previous).cwiseAbs().maxCoeff();
    const int needed = static_cast<int>(std::ceil(distance / MaxStep(envelope.limits(), 0.01)));
    for (int step = 0; step <= needed; ++step) {
      input.previous = GateCommand(envelope, watchdog, input).command;
    }
    EXPECT_LT((input.previous - goal).norm(), 1e-9) << "after " << needed + 1 << " steps";
  }
}

TEST(SafetyGateTest, RaisingTensionBendsNothing) {
  // A proposal with slack tendons is tightened along the pretension
  // direction: the model's curvatures stay those of the proposal.
  const TendonModel model(testing::CatheterOptions());
  SafetyLimits limits;
  limits.max_rate = 1e6;  // no rate limit here
  limits.range = {-10.0, 10.0};
  const SafetyEnvelope envelope(model, limits);
  std::mt19937_64 rng(15);
  std::uniform_real_distribution<double> u(-1.0, 2.0);
  int checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    GateInput input;
    input.previous = envelope.RestingCommand();
    input.proposal = Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng));
    input.dt = 0.01;
    const GateResult result = GateCommand(envelope, WatchdogOptions{}, input);
    if (envelope.Tensions(input.proposal).minCoeff() >= limits.min_tension) continue;
    if (result.has(kGateClampedToRange)) continue;  // the raise met a range's end
    ++checked;
    EXPECT_TRUE(result.has(kGateRaisedForTension)) << DescribeGateReasons(result.reasons);
    EXPECT_FALSE(result.has(kGateRateLimited));
    EXPECT_LT((model.Forward(result.command) - model.Forward(input.proposal)).head<2>().norm(),
              1e-12);
    EXPECT_NEAR(envelope.Tensions(result.command).minCoeff(), limits.min_tension, 1e-8);
  }
  EXPECT_GT(checked, 100);
}

TEST(SafetyGateTest, HoldsOnStaleSensingAndResumesByItself) {
  const TendonModel model(testing::CatheterOptions());
  const SafetyLimits limits;
  SafetyGate gate(model, limits, WatchdogOptions{}, SafetyEnvelope(model, limits).RestingCommand());
  const Eigen::VectorXd start = gate.command();
  const Eigen::VectorXd proposal = start + Eigen::Vector4d(0.5, 0.0, 0.0, 0.0);
  EXPECT_TRUE(gate.Apply(proposal, 0.01, kInf, false).has(kGateAwaitingSensing));
  EXPECT_FALSE(gate.stopped()) << "nothing sensed yet is no loss";
  EXPECT_FALSE(gate.Apply(proposal, 0.01, 0.05, false).held);
  const Eigen::VectorXd moved = gate.command();
  EXPECT_NE(moved, start);
  const GateResult stale = gate.Apply(proposal, 0.01, 0.3, false);
  EXPECT_TRUE(stale.held && stale.has(kGateSensingStale));
  EXPECT_EQ(gate.command(), moved);
  EXPECT_FALSE(gate.stopped());
  EXPECT_FALSE(gate.Apply(proposal, 0.01, 0.05, false).held) << "fresh sensing resumes";
}

TEST(SafetyGateTest, LostSensingAndEmergencyStopLatchUntilRearmed) {
  const TendonModel model(testing::CatheterOptions());
  const SafetyLimits limits;
  for (const bool use_estop : {false, true}) {
    SafetyGate gate(model, limits, WatchdogOptions{},
                    SafetyEnvelope(model, limits).RestingCommand());
    const Eigen::VectorXd proposal = gate.command() + Eigen::Vector4d(0.5, 0.0, 0.0, 0.0);
    gate.Apply(proposal, 0.01, 0.05, false);
    const Eigen::VectorXd before = gate.command();
    const GateResult stop =
        use_estop ? gate.Apply(proposal, 0.01, 0.05, true) : gate.Apply(proposal, 0.01, 1.5, false);
    EXPECT_TRUE(stop.held);
    EXPECT_TRUE(stop.has(use_estop ? kGateEmergencyStop : kGateSensingLost));
    EXPECT_TRUE(gate.stopped());
    if (use_estop) {
      gate.Apply(proposal, 0.01, 0.05, true);
      EXPECT_EQ(gate.Rearm(), "the emergency stop is engaged");
    } else {
      EXPECT_EQ(gate.Rearm(), "the sensing is not fresh");
    }
    // Conditions back to normal: still stopped until re-armed.
    const GateResult latched = gate.Apply(proposal, 0.01, 0.05, false);
    EXPECT_TRUE(latched.held && latched.has(kGateStoppedUntilRearmed));
    EXPECT_EQ(gate.command(), before);
    EXPECT_EQ(gate.Rearm(), "");
    EXPECT_FALSE(gate.Apply(proposal, 0.01, 0.05, false).held);
    EXPECT_NE(gate.command(), before);
  }
}

TEST(SafetyGateTest, ExplainsItself) {
  EXPECT_EQ(DescribeGateReasons(0), "");
  EXPECT_EQ(DescribeGateReasons(kGateClampedToRange | kGateRateLimited),
            "clamped to range, rate limited");
  const TendonModel model(testing::CatheterOptions());
  const SafetyEnvelope envelope(model, SafetyLimits{});
  EXPECT_NE(envelope.Check(Eigen::Vector4d(9.0, 1.0, 1.0, 1.0)).find("tendon 0: 9 mm outside"),
            std::string::npos);
  EXPECT_NE(envelope.Check(Eigen::Vector4d::Zero()).find("below the minimum"), std::string::npos);
  EXPECT_NE(envelope.Check(Eigen::Vector3d::Zero()).find("expected 4"), std::string::npos);
}

TEST(SafetyGateTest, RefusesLimitsThatDoNotFitTheModel) {
  const TendonModel model(testing::CatheterOptions());
  SafetyLimits limits;
  limits.tendon_ranges = {{0.0, 1.0}, {0.0, 1.0}};
  EXPECT_THROW(SafetyEnvelope(model, limits), std::invalid_argument);
  GateInput input;
  input.previous = Eigen::Vector3d::Zero();
  EXPECT_THROW(GateCommand(SafetyEnvelope(model, SafetyLimits{}), WatchdogOptions{}, input),
               std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
