// The closed-loop experiment end to end, inside this test's private network
// namespace (tests/support): the rig-sim in plant mode (a tendon plant 20%
// off the controller's model, with play on its tendons) behind three fake
// GigE cameras, capture, carving, shape sensing q and lcm-logger as separate
// programs over UDP multicast; shapesense-controller drives the plant through
// 12 targets across the workspace, in open loop and then closed loop on the
// sensed shape. The same code as `shapesense demo`
// (clients/tools/demo/closed_loop_experiment.h).
//
// Closed loop must bring the true tip (the rig's truth, not the sensing)
// within 1 mm of its targets at steady state where open loop does not, and
// no command that went out may break a limit.
//
// Throughout, an attacker without the key (`shapesense attack`) sits on the
// same multicast group and publishes forged targets, shapes and plant
// commands, bit-flipped ones and replays of real ones (docs/security.md).
// None may be acted on: the bounds above are those of a run without it,
// every kind of forgery is rejected for its reason, and no forged target,
// shape or plant command, nor a command computed from a forged shape,
// reaches a handler.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <sstream>

#include "clients/tools/demo/closed_loop_experiment.h"
#include "tests/e2e/live_pipeline.h"
#include "tests/support/network_test.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;

class ClosedLoopTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(nettest::PrivateNetworkError(), "");
    out_ = fs::path(::testing::TempDir()) / ("closed_loop_test_" + std::to_string(getpid()));
    fs::remove_all(out_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(out_);
  }

  ExperimentArgs Args() const {
    ExperimentArgs args;
    args.out = out_;
    args.config_dir = fs::path(SHAPESENSE_SOURCE_DIR) / "config";
    args.bin_dir = E2E_BIN_DIR;
    args.network = "the test's private network namespace";
    args.progress = DemoProgress::kLines;
    return args;
  }

  fs::path out_;
};

void ExpectEveryRunClean(const ExperimentReport& report, const std::string& log) {
  EXPECT_EQ(report.failure, "") << log;
  EXPECT_FALSE(report.interrupted);
  for (const ExperimentRun& run : report.runs) {
    EXPECT_EQ(run.targets_sent, static_cast<int>(report.targets.size())) << run.score.mode;
    EXPECT_EQ(run.score.targets_scored, static_cast<int>(report.targets.size()))
        << run.score.mode << ": every target's steady state seen by the rig's truth";
    EXPECT_GT(run.commands, 100) << run.score.mode;
    EXPECT_EQ(run.violations.total(), 0) << run.score.mode << ": " << run.first_violation;
    EXPECT_TRUE(run.end.clean) << run.score.mode << ": the controller " << run.end.how;
  }
  for (const ProgramEnd& program : report.programs) {
    EXPECT_TRUE(program.clean) << program.name << " " << program.how;
  }
}

int64_t Count(const std::map<std::string, int64_t>& counts, const std::string& key) {
  const auto found = counts.find(key);
  return found == counts.end() ? 0 : found->second;
}

void ExpectEveryForgeryRejected(const ExperimentReport& report) {
  EXPECT_TRUE(report.auth.starts_with("on (key")) << report.auth;
  ASSERT_TRUE(report.attack.has_value());
  const AttackReport& attack = *report.attack;
  EXPECT_EQ(attack.error, "");
  EXPECT_GT(attack.sent, 100);
  for (const char* kind : {"unsigned_target", "foreign_key_shape", "forged_mac_plant_command",
                           "replayed_shape", "flipped_shape", "replayed_old_plant_command"}) {
    EXPECT_GT(attack.sent_by_kind.value(kind, 0), 0) << kind;
  }
  EXPECT_EQ(attack.accepted, 0) << nlohmann::json(attack.accepted_by_kind).dump();
  for (const char* reason : {"unsigned", "unknown_key", "bad_mac"}) {
    EXPECT_GT(Count(attack.rejected_by_reason, reason), 0) << reason;
  }
  EXPECT_GT(
      Count(attack.rejected_by_reason, "replayed") + Count(attack.rejected_by_reason, "too_old"),
      0);
  // The programs that act on what moves the robot refused it themselves.
  EXPECT_GT(Count(attack.rejected_by_program, "controller"), 0);
  EXPECT_GT(Count(attack.rejected_by_program, "rig_sim"), 0);
}

TEST_F(ClosedLoopTest, ClosedLoopReachesTheTargetsWithinAMillimetreWhereOpenLoopDoesNot) {
  ExperimentArgs args = Args();
  if (e2e::UnderSanitizers()) {
    // Rendering runs about three times slower: the rig at 10 Hz, fewer and
    // longer holds. The limits and the clean runs are checked as in
    // Release; the accuracy only against open loop (the sensing is slower
    // than the controller's watchdog wants, so it holds often).
    std::cout << "under sanitizers: " << e2e::LiveRate()
              << " Hz, 4 targets of 8 s, the watchdog at 0.6 s / 3 s; the 1 mm bound is "
                 "checked in Release builds"
              << std::endl;
    args.rate_hz = e2e::LiveRate();
    args.config_dir = e2e::ConfigWithSlowerWatchdog(args.config_dir, out_ / "config");
    args.targets.count = 4;
    args.targets.hold_s = 8.0;
  } else {
    args.targets.count = 12;  // the demo runs 20; 12 give a steady mean in less time
    args.targets.hold_s = 5.0;
  }
  args.attacker = true;
  std::ostringstream log;
  const std::atomic<bool> stop{false};
  const ExperimentReport report = RunClosedLoopExperiment(args, stop, log);
  std::cout << log.str();
  ASSERT_EQ(report.runs.size(), 2u);
  ExpectEveryRunClean(report, log.str());
  ExpectEveryForgeryRejected(report);
  const ExperimentRun& open = *report.Run("open_loop");
  const ExperimentRun& closed = *report.Run("closed_loop");
  std::cout << "open loop " << open.score.mean_tip_error_mm << " mm ("
            << open.score.mean_tip_error_percent << "% of L1), closed loop "
            << closed.score.mean_tip_error_mm << " mm (" << closed.score.mean_tip_error_percent
            << "% of L1)" << std::endl;
  EXPECT_LT(closed.score.mean_tip_error_mm, open.score.mean_tip_error_mm / 2.0);
  if (!e2e::UnderSanitizers()) {
    EXPECT_GT(open.score.mean_tip_error_mm, 1.0) << "the plant is off the model";
    EXPECT_LE(closed.score.mean_tip_error_mm, 1.0);
  }
  EXPECT_TRUE(fs::exists(out_ / "report.json"));
  EXPECT_TRUE(fs::exists(out_ / "tip_paths.png"));
  EXPECT_TRUE(fs::exists(out_ / "closed_loop" / "controller_log.csv"));
}

}  // namespace
}  // namespace shapesense
