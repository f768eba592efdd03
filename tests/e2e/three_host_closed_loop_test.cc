// The closed-loop experiment over three hosts (network namespaces on a
// bridge, clients/tools/demo/demo_hosts.h), as `shapesense demo --hosts 3`
// runs it: the rig-sim, capture, carving and shape on the camera host, the
// controller on the control host, the logger, `rig status` and the
// experimenter on the operator host. Only compact messages cross the rig
// network (ttl=1); the images stay on the camera host. The rig network
// crosses hosts, so every program holds the run's key and signs and
// verifies the targets, commands and shapes (docs/security.md): the clock
// offsets below must not break that.
//
//   - The camera host's clock +0.5 s, then -0.5 s off: the controller closes
//     the loop as well as with synchronised clocks, each host measures the
//     offset, and no image crosses.
//   - Faults in one run: the control host's link pulled for 2 s (the
//     controller holds, stops once its sensing is lost, and moves again only
//     after the operator's release), the shape service killed (restarted by
//     its supervisor, the outage measured), the logger restarted (its log
//     keeps every frame-set before and after, the gap counted); no
//     command breaks a limit or goes out on stale sensing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "clients/tools/demo/closed_loop_experiment.h"
#include "clients/tools/demo/demo_hosts.h"
#include "runtime/file_io.h"
#include "tests/e2e/live_pipeline.h"
#include "tests/support/network_test.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;

// The controller's watchdog (config/controller.yaml; slower under sanitizers).
constexpr double kHoldAgeS = 0.2;
constexpr double kLostAgeS = 1.0;
constexpr double kSanitizerHoldAgeS = 0.6;
constexpr double kSanitizerLostAgeS = 3.0;

class ThreeHostClosedLoopTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(nettest::PrivateNetworkError(), "");
    out_ = fs::path(::testing::TempDir()) / ("three_host_closed_loop_" + std::to_string(getpid()));
    fs::remove_all(out_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(out_);
  }

  ExperimentArgs Args(const std::string& name) const {
    ExperimentArgs args;
    args.out = out_ / name;
    args.config_dir = fs::path(SHAPESENSE_SOURCE_DIR) / "config";
    args.bin_dir = E2E_BIN_DIR;
    args.network = "three hosts in the test's private network namespace";
    args.progress = DemoProgress::kLines;
    args.modes = {"closed_loop"};
    args.targets.count = 8;
    args.targets.hold_s = 5.0;
    if (e2e::UnderSanitizers()) {
      args.rate_hz = e2e::LiveRate();
      args.config_dir = e2e::ConfigWithSlowerWatchdog(args.config_dir, out_ / (name + "_config"));
      args.targets.count = 4;
      args.targets.hold_s = 8.0;
    }
    return args;
  }

  // One experiment on fresh hosts, the camera host's clock `offset_ms` off.
  ExperimentReport Run(ExperimentArgs args, double offset_ms) {
    const VirtualHosts hosts(DemoHostSpecs(offset_ms, 3));
    args.hosts = &hosts;
    std::ostringstream log;
    const std::atomic<bool> stop{false};
    ExperimentReport report = RunClosedLoopExperiment(args, stop, log);
    std::cout << log.str() << std::endl;
    EXPECT_EQ(report.failure, "") << log.str();
    return report;
  }

  fs::path out_;
};

double OffsetSeen(const RigNetworkReport& rig, const std::string& by, const std::string& of) {
  const auto host = rig.clock_offsets_ms.find(by);
  if (host == rig.clock_offsets_ms.end()) return std::nan("");
  const auto offset = host->second.find(of);
  return offset == host->second.end() ? std::nan("") : offset->second;
}

// The controller's sensing age over its run, from its step log.
double MedianSensingAge(const ExperimentReport& report) {
  const fs::path csv = report.log.parent_path() / "closed_loop" / "controller_log.csv";
  std::vector<double> ages;
  for (const ControllerStep& step : ParseControllerSteps(ReadTextFile(csv), csv.string())) {
    if (step.mode == "closed_loop") ages.push_back(step.sensing_age_s);
  }
  if (ages.empty()) return std::nan("");
  std::nth_element(ages.begin(), ages.begin() + static_cast<long>(ages.size() / 2), ages.end());
  return ages[ages.size() / 2];
}

double RunSeconds(const ExperimentReport& report) { return report.targets.back().end_s; }

// What every run on three hosts must show.
void ExpectACleanRigRun(const ExperimentReport& report, double camera_offset_ms) {
  ASSERT_TRUE(report.rig.has_value());
  const RigNetworkReport& rig = *report.rig;
  ASSERT_EQ(report.runs.size(), 1u);
  EXPECT_TRUE(report.auth.starts_with("on (key")) << report.auth;
  const ExperimentRun& run = report.runs[0];
  EXPECT_EQ(run.violations.total(), 0) << run.first_violation;
  EXPECT_GT(run.commands, 100);
  EXPECT_TRUE(run.end.clean) << run.end.how;
  EXPECT_EQ(run.score.targets_scored, static_cast<int>(report.targets.size()));
  // No image crossed; the shapes, truth, commands and status did.
  EXPECT_EQ(rig.image_messages, 0);
  for (const char* channel : {"SHAPESENSE_SHAPE", "SHAPESENSE_TRUTH", "SHAPESENSE_TENDON_COMMAND",
                              "SHAPESENSE_STATUS_controller"}) {
    EXPECT_GT(rig.channel_messages.count(channel), 0u) << channel << " never crossed";
  }
  for (const char* channel : {"SHAPESENSE_VOXELS", "SHAPESENSE_SILHOUETTES"}) {
    EXPECT_EQ(rig.channel_messages.count(channel), 0u)
        << channel << " stays on the camera host, where carving and shape run";
  }
  // Compact messages only: far below the images' ~80 MB/s at 30 Hz.
  EXPECT_GT(rig.received_bytes_per_s, 0.0);
  EXPECT_LT(rig.received_bytes_per_s, 1e6);
  // Each host measured the camera host's clock.
  EXPECT_NEAR(OffsetSeen(rig, kControlHostName, kCameraHostName), camera_offset_ms, 20.0);
  EXPECT_NEAR(OffsetSeen(rig, kCameraHostName, kControlHostName), -camera_offset_ms, 20.0);
  // `rig status` on the operator host saw every expected program up.
  EXPECT_NE(rig.rig_status_end.find("status 0"), std::string::npos) << rig.rig_status_end << "\n"
                                                                    << rig.rig_status.dump(2);
  // Every program ended cleanly (but the run the faults killed, restarted).
  for (const ProgramEnd& program : report.programs) {
    if (program.how.ends_with(", restarted")) continue;
    EXPECT_TRUE(program.clean) << program.name << " " << program.how;
  }
}

TEST_F(ThreeHostClosedLoopTest, TheCameraClockHalfASecondOffChangesNothing) {
  if (e2e::UnderSanitizers()) {
    // Three runs at 5 Hz would take minutes each: under sanitizers the fault
    // run below has the camera clock +0.5 s and makes every other check.
    GTEST_SKIP() << "under sanitizers the fault run carries the camera clock +0.5 s; the "
                    "comparison with synchronised clocks and the 1 mm bound run in Release";
  }
  const ExperimentReport synchronised = Run(Args("synchronised"), 0.0);
  const ExperimentReport ahead = Run(Args("ahead"), 500.0);
  const ExperimentReport behind = Run(Args("behind"), -500.0);
  ExpectACleanRigRun(synchronised, 0.0);
  ExpectACleanRigRun(ahead, 500.0);
  ExpectACleanRigRun(behind, -500.0);
  const double reference = synchronised.runs.at(0).score.mean_tip_error_mm;
  const double reference_age = MedianSensingAge(synchronised);
  std::cout << "closed-loop mean tip error: synchronised " << reference << " mm, camera +0.5 s "
            << ahead.runs.at(0).score.mean_tip_error_mm << " mm, camera -0.5 s "
            << behind.runs.at(0).score.mean_tip_error_mm << " mm; the controller's median "
            << "sensing age " << reference_age * 1e3 << ", " << MedianSensingAge(ahead) * 1e3
            << ", " << MedianSensingAge(behind) * 1e3 << " ms" << std::endl;
  for (const ExperimentReport* report : {&synchronised, &ahead, &behind}) {
    const ExperimentRun& run = report->runs.at(0);
    EXPECT_LE(run.score.mean_tip_error_mm, 1.0);
    // The closed loop's run-to-run noise over 8 targets is a few tenths of a
    // millimetre (the plant's play now and then leaves a target 1-2 mm off);
    // a controller that took stale shapes or held would be millimetres off.
    EXPECT_NEAR(run.score.mean_tip_error_mm, reference, 0.5);
    // The sensing as fresh as with synchronised clocks: a controller that
    // compared the camera's clock with its own would see it 0.5 s off. (On
    // an idle machine the three runs' medians agree within 2 ms, 46-47 ms;
    // a busy one, CI's sanitizer build beside the test, moves them between
    // runs by tens of ms, so the bound is a fifth of the offset it catches.)
    EXPECT_NEAR(MedianSensingAge(*report), reference_age, 0.1);
    // The shapes kept coming (85-95% of the frame-sets, as busy as the
    // machine is): a controller whose checks refused the other host's
    // shapes would have none.
    EXPECT_GT(run.shapes, 0.5 * report->rate_hz * RunSeconds(*report));
    // A controller that compared the camera's clock with its own would find
    // every shape half a second old: it would hold from the start and stop
    // for good, which the sensing age and the shapes above catch. A stop
    // for lost sensing while a busy machine drops frame-sets for a second
    // (seen once with one core kept busy) is the gate doing its job, and the
    // operator's release brings it back; more than one would not be chance.
    EXPECT_LE(report->rig->releases, 1) << "the controller stopped again and again";
  }
}

const FaultOutcome* FaultOf(const RigNetworkReport& rig, FaultKind kind) {
  for (const FaultOutcome& fault : rig.faults) {
    if (fault.event.fault.kind == kind) return &fault;
  }
  return nullptr;
}

TEST_F(ThreeHostClosedLoopTest, ALinkDownAKilledServiceAndARestartedLoggerAreSurvived) {
  ExperimentArgs args = Args("faults");
  args.targets.count = 4;
  args.faults = StandardFaults(args.targets.count);
  const double hold_age = e2e::UnderSanitizers() ? kSanitizerHoldAgeS : kHoldAgeS;
  const double lost_age = e2e::UnderSanitizers() ? kSanitizerLostAgeS : kLostAgeS;
  // Under sanitizers this run also stands for the clock test above.
  const double camera_offset_ms = e2e::UnderSanitizers() ? 500.0 : 0.0;
  const ExperimentReport report = Run(args, camera_offset_ms);
  ExpectACleanRigRun(report, camera_offset_ms);
  const RigNetworkReport& rig = *report.rig;
  ASSERT_EQ(rig.faults.size(), 3u);
  for (const FaultOutcome& fault : rig.faults) {
    EXPECT_EQ(fault.conduct.sent_on_stale, 0) << FaultName(fault.event.fault.kind);
  }

  // The link down 2 s: held once the sensing was hold_age old, stopped once
  // lost, moved again after the release.
  const FaultOutcome* link = FaultOf(rig, FaultKind::kControlLinkDown);
  ASSERT_NE(link, nullptr);
  const ControllerConduct& c = link->conduct;
  EXPECT_NEAR(static_cast<double>(link->event.end_utime - link->event.start_utime) * 1e-6, 2.0,
              0.2);
  EXPECT_GE(c.first_hold_after_s, 0.0);
  EXPECT_LE(c.first_hold_after_s, hold_age + 0.1);
  if (lost_age < 2.0) {
    EXPECT_GT(c.stopped_steps, 0);
    EXPECT_LE(c.first_stop_after_s, lost_age + 0.1);
    EXPECT_GE(rig.releases, 1);
  }
  EXPECT_GE(c.resumed_after_s, 0.0) << "the controller moved again";
  EXPECT_LT(c.resumed_after_s, 2.0);

  // The shape service killed: restarted, the outage measured.
  const FaultOutcome* killed = FaultOf(rig, FaultKind::kKillShape);
  ASSERT_NE(killed, nullptr);
  EXPECT_EQ(killed->restarts, 1);
  int restarted = 0;
  for (const ProgramEnd& program : report.programs)
    restarted += program.how.ends_with(", restarted");
  EXPECT_EQ(restarted, 1);
  EXPECT_GT(killed->sensing_outage_s, 0.0);
  if (!e2e::UnderSanitizers()) {
    EXPECT_LE(killed->sensing_outage_s, 2.0);
  }
  // A restart quicker than the hold age leaves the sensing fresh enough to
  // go on; a slower one makes the controller hold (no command goes out on
  // stale sensing: checked above for every fault) and move again after.
  if (killed->conduct.max_sensing_age_s >= hold_age) {
    EXPECT_GE(killed->conduct.held_steps + killed->conduct.stopped_steps, 1);
    EXPECT_GE(killed->conduct.resumed_after_s, 0.0) << "the controller moved again";
  }

  // The logger restarted: every frame-set's truth before and after, the gap counted.
  const FaultOutcome* logger = FaultOf(rig, FaultKind::kRestartLogger);
  ASSERT_NE(logger, nullptr);
  EXPECT_EQ(logger->log.missing_within_runs, 0);
  EXPECT_GT(logger->log.messages, report.rate_hz * 10.0);
  EXPECT_LT(logger->log.gap_between_runs, report.rate_hz * 3.0);
  std::cout << "link down: held after " << c.first_hold_after_s << " s, stopped after "
            << c.first_stop_after_s << " s, moved again " << c.resumed_after_s
            << " s after the link came back; shape service killed: outage "
            << killed->sensing_outage_s << " s; logger restarted: " << logger->log.gap_between_runs
            << " frame-sets not logged" << std::endl;
}

}  // namespace
}  // namespace shapesense
