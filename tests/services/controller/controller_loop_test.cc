// The controller service in process over LCM memq://, on a simulated clock,
// against the fake plant peer (the tendon plant with stiffnesses 20% off the
// model and tendon play, sensed with noise at 30 Hz, 60 ms late): closed
// loop reaches targets open loop misses; stale sensing holds within the
// watchdog age and lost sensing stops; an e-stop stops at once and stays
// latched until a release; a cut actuator link stops with a clear error;
// malformed targets and shapes are rejected with a reason. Every command in
// every log is checked against the limits again, from the log alone. The
// numbers are printed (docs/controller.md quotes them).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <numbers>
#include <thread>

#include "libs/mechanics/configuration_geometry.h"
#include "runtime/lcm/channels.h"
#include "shapesense/estop_t.hpp"
#include "shapesense/tendon_command_t.hpp"
#include "tests/services/controller/controller_log_check.h"
#include "tests/services/controller/in_process_rig.h"

namespace shapesense {
namespace {

using ::testing::HasSubstr;
using testing::InProcessRig;

constexpr double kHold = 8.0;  // s per target
constexpr double kDt = 0.01;   // the default loop_rate's period
constexpr int8_t kModeStop = tendon_command_t::MODE_STOP;

// Bends of 0.4 to 1.3 rad toward directions a golden angle apart, each held kHold.
std::vector<Target> WorkspaceTargets(int count, const ManipulatorOptions& model) {
  std::vector<Target> targets;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < count; ++k) {
    Target target;
    target.time = k * kHold;
    const double bend = 0.4 + 0.9 * ((k * 3) % count) / std::max(1, count - 1);
    target.configuration.head<2>() = CurvatureTowards(k * golden + 0.3, bend, model.distal_length);
    targets.push_back(target);
  }
  return targets;
}

testing::FakeRigOptions OffNominalRig() {
  testing::FakeRigOptions rig;
  rig.plant = testing::OffNominalPlant();
  return rig;
}

// The logs as written: every command within the limits, one CSV row and one
// command and one state event per step. Returns the check of the commands.
testing::LimitCheck ExpectLogsComplete(InProcessRig& rig) {
  EXPECT_EQ(rig.log().Flush(), "");
  const testing::ControllerCsv csv = testing::ReadControllerCsv(rig.setup().client.log.csv);
  EXPECT_EQ(csv.bad_rows, 0);
  EXPECT_EQ(static_cast<int64_t>(csv.rows.size()), rig.client().counters().steps);
  testing::LimitCheck check = testing::CheckLoggedCommands(
      csv, TendonModel(rig.setup().manipulator), rig.setup().controller.limits);
  EXPECT_EQ(check.total(), 0) << check.first;
  EXPECT_EQ(check.commands, static_cast<int>(csv.rows.size()));
  std::map<std::string, int64_t> events;
  lcm::LogFile log(rig.setup().client.log.lcm, "r");
  EXPECT_TRUE(log.good());
  while (const lcm::LogEvent* event = log.readNextEvent()) ++events[event->channel];
  EXPECT_EQ(events[channels::kTendonCommand], static_cast<int64_t>(csv.rows.size()));
  EXPECT_EQ(events[channels::kTendonState], static_cast<int64_t>(csv.rows.size()));
  EXPECT_GT(events[channels::kShape], 0);
  return check;
}

// Started at rest (every tendon at the minimum tension): no command below it.
void ExpectLogsWithinLimits(InProcessRig& rig) {
  EXPECT_EQ(ExpectLogsComplete(rig).below_floor, 0);
}

struct TipErrors {
  std::vector<double> mean;  // per target, over the last second of its hold, mm
  std::vector<double> max;
};

TipErrors RunTargets(InProcessRig& rig) {
  const std::vector<ResolvedTarget>& targets = rig.setup().trajectory.targets;
  const SectionLengths lengths = TendonModel(rig.setup().manipulator).lengths();
  TipErrors errors{std::vector<double>(targets.size(), 0.0),
                   std::vector<double>(targets.size(), 0.0)};
  const int window = static_cast<int>(std::lround(1.0 / kDt));
  for (size_t k = 0; k < targets.size(); ++k) {
    const Vec3 target_tip = BaseFromTip(targets[k].configuration, lengths).translation();
    for (int step = 0; step < static_cast<int>(std::lround(kHold / kDt)); ++step) {
      rig.Step();
      if (step < static_cast<int>(std::lround(kHold / kDt)) - window) continue;
      const double error = (rig.plant().TrueTip() - target_tip).norm();
      errors.mean[k] += error / window;
      errors.max[k] = std::max(errors.max[k], error);
    }
  }
  return errors;
}

TEST(ControllerLoopTest, ClosedLoopReachesTargetsThatOpenLoopMisses) {
  const std::vector<Target> targets = WorkspaceTargets(6, testing::CatheterModel());
  std::map<ControlMode, TipErrors> results;
  for (const ControlMode mode : {ControlMode::kOpenLoop, ControlMode::kClosedLoop}) {
    const std::filesystem::path dir = testing::TestLogDir() / ControlModeName(mode);
    InProcessRig rig(testing::TrajectorySetup(mode, targets, dir), OffNominalRig());
    rig.Start();
    results[mode] = RunTargets(rig);
    rig.client().Finish("end of test");
    EXPECT_EQ(rig.client().error(), "");
    EXPECT_GT(rig.client().counters().shapes_used, 0);
    ExpectLogsWithinLimits(rig);
    for (size_t k = 0; k < targets.size(); ++k) {
      std::printf("%-11s target %zu: tip error mean %6.3f mm  max %6.3f mm\n",
                  ControlModeName(mode), k, results[mode].mean[k], results[mode].max[k]);
    }
  }
  int open_misses = 0;
  for (size_t k = 0; k < targets.size(); ++k) {
    EXPECT_LE(results[ControlMode::kClosedLoop].max[k], 1.0) << "closed loop, target " << k;
    if (results[ControlMode::kOpenLoop].mean[k] > 1.0) ++open_misses;
  }
  EXPECT_GE(open_misses, 5) << "open loop should miss the targets on this plant";
}

// Two targets far apart: the move to the second one takes seconds at max_rate.
std::vector<Target> OneMove() {
  std::vector<Target> targets(2);
  targets[0].configuration.head<2>() = CurvatureTowards(0.0, 0.3, 160.0);
  targets[1].time = kHold;
  targets[1].configuration.head<2>() = CurvatureTowards(std::numbers::pi, 1.0, 160.0);
  return targets;
}

TEST(ControllerLoopTest, SensingStoppedMidMoveHoldsWithinTheWatchdogAgeThenStops) {
  for (const ControlMode mode :
       {ControlMode::kOpenLoop, ControlMode::kClosedLoop, ControlMode::kModelLess}) {
    const std::filesystem::path dir = testing::TestLogDir() / ControlModeName(mode);
    InProcessRig rig(testing::TrajectorySetup(mode, OneMove(), dir), OffNominalRig());
    const WatchdogOptions& watchdog = rig.setup().controller.watchdog;
    rig.Start();
    rig.RunFor(kHold + 0.5);
    rig.plant().set_sensing(false);
    const int64_t moves_before = rig.plant().moves();
    double last_motion = 0.0, first_stop = -1.0;
    Eigen::VectorXd previous = rig.client().last_step().command;
    uint32_t reasons = 0;
    rig.RunFor(watchdog.lost_age + 1.0, [&](const StepRecord& step) {
      if (step.command != previous) last_motion = step.time;
      if (step.mode == tendon_command_t::MODE_STOP && first_stop < 0.0) first_stop = step.time;
      previous = step.command;
      reasons |= step.reasons;
    });
    const double last_trigger = rig.SecondsOf(rig.plant().last_trigger_utime());
    std::printf(
        "%-11s last sample at %.3f s; last motion %.3f s later (hold_age %.2f s); "
        "stopped %.3f s after the last sample (lost_age %.2f s)\n",
        ControlModeName(mode), last_trigger, last_motion - last_trigger, watchdog.hold_age,
        first_stop - last_trigger, watchdog.lost_age);
    EXPECT_GT(last_motion, kHold + 0.5) << "it was moving when the sensing stopped";
    EXPECT_LE(last_motion, last_trigger + watchdog.hold_age + kDt + 1e-9);
    EXPECT_GE(first_stop, last_trigger + watchdog.lost_age - 1e-9);
    EXPECT_LE(first_stop, last_trigger + watchdog.lost_age + kDt + 1e-9);
    EXPECT_TRUE(reasons & kGateSensingStale);
    EXPECT_TRUE(reasons & kGateSensingLost);
    EXPECT_TRUE(rig.client().gate().stopped());
    EXPECT_GE(rig.plant().stops(), 1) << "the driver was told to stop";
    EXPECT_LE(rig.plant().moves() - moves_before,
              static_cast<int64_t>(std::lround((watchdog.hold_age + kDt) / kDt)) + 1);
    EXPECT_THAT(rig.progress(), HasSubstr("stopped (sensing lost)"));
    ExpectLogsWithinLimits(rig);
  }
}

estop_t EmergencyStop(bool engaged) {
  estop_t estop{};
  estop.engaged = engaged;
  estop.reason = engaged ? "operator pressed the button" : "cleared";
  estop.source = "test console";
  return estop;
}

TEST(ControllerLoopTest, AnEmergencyStopStopsAtOnceAndStaysLatchedUntilReleased) {
  InProcessRig rig(
      testing::TrajectorySetup(ControlMode::kClosedLoop, OneMove(), testing::TestLogDir()),
      OffNominalRig());
  rig.Start();
  rig.RunFor(kHold + 0.3);  // mid-move
  ASSERT_TRUE(rig.client().last_step().sent);
  rig.bus().Publish(channels::kEstop, EmergencyStop(true));
  rig.client().DrainBus();
  // Before any further step: the driver has stopped the plant.
  EXPECT_EQ(rig.plant().stops(), 1);
  EXPECT_TRUE(rig.client().emergency_stop_engaged());
  const int64_t moves = rig.plant().moves();
  const Eigen::VectorXd frozen = rig.client().last_step().command;
  int fresh_steps = 0;
  rig.RunFor(3.0, [&](const StepRecord& step) {
    EXPECT_FALSE(step.sent);
    EXPECT_EQ(step.mode, kModeStop);
    EXPECT_EQ(step.command, frozen);
    if (step.sensing_age < rig.setup().controller.watchdog.hold_age) ++fresh_steps;
  });
  EXPECT_EQ(rig.plant().moves(), moves);
  EXPECT_EQ(fresh_steps, 300) << "latched although the sensing stayed fresh";
  EXPECT_TRUE(rig.client().gate().stopped());

  rig.bus().Publish(channels::kEstop, EmergencyStop(false));
  int sent = 0;
  rig.RunFor(1.0, [&](const StepRecord& step) { sent += step.sent ? 1 : 0; });
  EXPECT_GT(sent, 90) << "moving again after the release";
  EXPECT_GT(rig.plant().moves(), moves);
  EXPECT_THAT(rig.progress(), HasSubstr("e-stop engaged by test console: operator pressed"));
  EXPECT_THAT(rig.progress(), HasSubstr("re-armed"));
  ExpectLogsWithinLimits(rig);
}

TEST(ControllerLoopTest, ACutActuatorLinkStopsWithAClearError) {
  InProcessRig rig(
      testing::TrajectorySetup(ControlMode::kClosedLoop, OneMove(), testing::TestLogDir()),
      OffNominalRig());
  std::vector<std::pair<double, int8_t>> plant_commands;  // (time, mode) on the plant link
  rig.bus().Subscribe<tendon_command_t>(
      channels::kPlantCommand, [&](tendon_command_t&& command, const std::string&, int64_t) {
        plant_commands.emplace_back(rig.time(), command.mode);
      });
  rig.Start();
  rig.RunFor(kHold + 0.3);
  const double cut = rig.time();
  rig.plant().set_answering(false);
  double failed_at = -1.0;
  rig.RunFor(2.0, [&](const StepRecord& step) {
    if (failed_at < 0.0 && !rig.client().error().empty()) failed_at = step.time;
  });
  const double timeout = rig.setup().actuators.rig.state_timeout_s;
  std::printf("link cut at %.3f s; the controller stopped %.3f s later (state_timeout_s %.2f s)\n",
              cut, failed_at - cut, timeout);
  ASSERT_GT(failed_at, 0.0);
  EXPECT_LE(failed_at - cut, timeout + 2 * kDt + 1e-9);
  EXPECT_THAT(rig.client().error(),
              HasSubstr("actuators (rig plant over LCM) failed: rig: link lost: no plant state"));
  EXPECT_EQ(rig.client().last_step().mode, kModeStop);
  for (const auto& [time, mode] : plant_commands) {
    // Sent at a step before the failure, handled by the next one.
    if (time > failed_at + kDt + 1e-9) {
      EXPECT_EQ(mode, kModeStop) << time;
    }
  }
  rig.client().Finish("end of test");
  EXPECT_FALSE(rig.client().error().empty()) << "a failure stays a failure";
  const testing::ControllerCsv csv = testing::ReadControllerCsv(rig.setup().client.log.csv);
  ASSERT_FALSE(csv.rows.empty());
  bool logged = false;
  for (size_t row = 0; row < csv.rows.size(); ++row) {
    logged = logged || csv.Text(row, "note").find("link lost") != std::string::npos;
  }
  EXPECT_TRUE(logged) << "the error is in the CSV log";
  ExpectLogsWithinLimits(rig);
}

TEST(ControllerLoopTest, FromASlackPowerUpTheGateHealsWithoutLooseningAnyTendon) {
  const std::vector<Target> targets = WorkspaceTargets(1, testing::CatheterModel());
  InProcessRig rig(
      testing::TrajectorySetup(ControlMode::kClosedLoop, targets, testing::TestLogDir()),
      OffNominalRig(), Eigen::VectorXd::Zero(4));
  rig.Start();
  rig.RunFor(4.0);
  rig.client().Finish("end of test");
  const testing::LimitCheck check = ExpectLogsComplete(rig);
  EXPECT_GT(check.below_floor, 0) << "it started slack";
  EXPECT_LT(check.below_floor, check.commands / 2) << "and healed";
  const SafetyLimits& limits = rig.setup().controller.limits;
  EXPECT_GE(rig.client().gate().envelope().Tensions(rig.client().gate().command()).minCoeff(),
            limits.min_tension - 1e-9);
}

configuration_target_t TargetMessage(double kappa_x, double kappa_z, double eps1) {
  configuration_target_t target{};
  target.kind = configuration_target_t::KIND_CONFIGURATION;
  target.q[0] = kappa_x;
  target.q[1] = kappa_z;
  target.q[3] = eps1;
  target.source = "test";
  return target;
}

// Raw bytes on a channel, as a broken or hostile sender would put them there.
struct RawBytes {
  std::vector<uint8_t> bytes;
  int encode(void* buffer, int offset, int max) const {
    if (max < static_cast<int>(bytes.size())) return -1;
    std::copy(bytes.begin(), bytes.end(), static_cast<uint8_t*>(buffer) + offset);
    return static_cast<int>(bytes.size());
  }
  int getEncodedSize() const { return static_cast<int>(bytes.size()); }
};

// A step, a wait (real time, bounded) until the tip solver's thread is
// done with what it was given, and a step that takes its results.
void StepPastTheTipSolver(InProcessRig& rig) {
  rig.Step();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (rig.client().resolving_targets() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  rig.Step();
}

TEST(ControllerLoopTest, MalformedAndUnreachableTargetsAreRejectedWithAReason) {
  InProcessRig rig(testing::StreamSetup(ControlMode::kClosedLoop, testing::TestLogDir()),
                   OffNominalRig());
  rig.Start();
  rig.RunFor(0.5);
  EXPECT_FALSE(rig.client().last_step().has_target);
  const ControllerCounters& counters = rig.client().counters();

  rig.bus().Publish(channels::kTarget, RawBytes{{0xde, 0xad, 0xbe, 0xef, 1, 2, 3, 4, 5, 6, 7, 8}});
  rig.Step();
  EXPECT_EQ(counters.messages_rejected, 1);
  EXPECT_THAT(counters.last_message_rejection,
              HasSubstr("SHAPESENSE_TARGET: not a valid configuration_target_t"));

  configuration_target_t tip_target = TargetMessage(0, 0, 0);
  tip_target.kind = configuration_target_t::KIND_TIP;
  tip_target.tip[0] = 500.0;  // half a metre to the side of a 760 mm manipulator
  configuration_target_t wrong_kind = TargetMessage(0.001, 0, 0.002);
  wrong_kind.kind = 7;
  configuration_target_t negative_duration = TargetMessage(0.001, 0, 0.002);
  negative_duration.duration_s = -1.0;
  const std::vector<std::pair<configuration_target_t, std::string>> bad = {
      {TargetMessage(std::nan(""), 0.0, 0.002), "q: expected finite numbers"},
      {TargetMessage(0.05, 0.0, 0.002), "curvature 0.05 /mm beyond the bound 0.0125 /mm"},
      {TargetMessage(0.001, 0.0, 0.3), "eps1 0.3: expected a compression in [0, 0.05]"},
      {tip_target, "tip: unreachable"},
      {wrong_kind, "kind: expected KIND_CONFIGURATION (1) or KIND_TIP (2), got 7"},
      {negative_duration, "duration_s: expected 0-3600 s"},
  };
  for (size_t i = 0; i < bad.size(); ++i) {
    rig.bus().Publish(channels::kTarget, bad[i].first);
    StepPastTheTipSolver(rig);
    EXPECT_EQ(counters.targets_rejected, static_cast<int64_t>(i + 1));
    EXPECT_THAT(counters.last_target_rejection, HasSubstr(bad[i].second));
    EXPECT_THAT(rig.progress(), HasSubstr("target rejected: " + bad[i].second));
    EXPECT_FALSE(rig.client().last_step().has_target);
  }

  // Shapes with a NaN q or a negative age are rejected too, and not used.
  shape_t shape{};
  shape.valid = shape.has_configuration = true;
  shape.trigger_utime = rig.now();
  shape.q[0] = std::nan("");
  rig.bus().Publish(channels::kShape, shape);
  shape.q[0] = 0.0;
  shape.header.data_age_us = -10'000'000;
  rig.bus().Publish(channels::kShape, shape);
  rig.Step();
  EXPECT_EQ(counters.shapes_rejected, 2);
  EXPECT_THAT(counters.last_shape_rejection, HasSubstr("data_age_us: expected 0 to"));

  EXPECT_EQ(rig.client().StatusSnapshot().rejected, 1 + 6 + 2);
  rig.RunFor(1.0);
  ExpectLogsWithinLimits(rig);
}

TEST(ControllerLoopTest, StreamedTargetsAreReachedAlongTheirRamp) {
  InProcessRig rig(testing::StreamSetup(ControlMode::kClosedLoop, testing::TestLogDir()),
                   OffNominalRig());
  rig.Start();
  rig.RunFor(0.5);
  const ControllerCounters& counters = rig.client().counters();
  // A configuration, reached over 2 s: half-way at 1 s.
  configuration_target_t good = TargetMessage(0.0, 0.004, 0.004);
  good.duration_s = 2.0;
  rig.bus().Publish(channels::kTarget, good);
  rig.Step();
  EXPECT_EQ(counters.targets_accepted, 1);
  const Configuration start = rig.client().last_step().target;
  rig.RunFor(1.0);
  const Configuration middle = rig.client().last_step().target;
  rig.RunFor(8.0);
  const Configuration end = rig.client().last_step().target;
  EXPECT_LT((middle - (start + end) / 2.0).norm(), 1e-6 * end.norm());
  EXPECT_NEAR(end(1), 0.004, 1e-12);
  const SectionLengths lengths = TendonModel(rig.setup().manipulator).lengths();
  EXPECT_LT((rig.plant().TrueTip() - BaseFromTip(end, lengths).translation()).norm(), 1.0);

  // A reachable tip target, through the tip solver's thread: reached.
  const Vec3 tip =
      BaseFromTip(testing::ResolvedConfiguration(rig.setup(), 0.003, -0.002, 0.004), lengths)
          .translation();
  configuration_target_t reachable = TargetMessage(0, 0, 0);
  reachable.kind = configuration_target_t::KIND_TIP;
  for (int i = 0; i < 3; ++i) reachable.tip[i] = tip(i);
  rig.bus().Publish(channels::kTarget, reachable);
  StepPastTheTipSolver(rig);
  EXPECT_EQ(counters.targets_accepted, 2);
  EXPECT_LT((BaseFromTip(rig.client().last_step().target, lengths).translation() - tip).norm(),
            rig.setup().controller.workspace.tip_tolerance);
  rig.RunFor(8.0);
  const double tip_error = (rig.plant().TrueTip() - tip).norm();
  std::printf("streamed tip target reached to %.3f mm\n", tip_error);
  EXPECT_LT(tip_error, 1.0);
  ExpectLogsWithinLimits(rig);
}

}  // namespace
}  // namespace shapesense
