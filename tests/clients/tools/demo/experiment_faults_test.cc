// The three-host demo's layout (demo_hosts.h) and the judging of its faults
// (experiment_faults.h) on made-up steps, files and times: the rig file it
// writes passes `rig check`; the controller's conduct, the logger's
// continuity and the sensing outage are read right, and the injector makes
// each fault once, at its time, and brings the link back.
#include <gtest/gtest.h>

#include <stdexcept>

#include "clients/tools/demo/demo_hosts.h"
#include "clients/tools/demo/experiment_faults.h"
#include "libs/core/error.h"
#include "runtime/rig/rig_check.h"

namespace shapesense {
namespace {

TEST(DemoHostsTest, TheRigFileItWritesPassesTheChecks) {
  AuthOptions auth;
  auth.key_files = {"/tmp/demo/setup/rig.key"};
  const std::string text =
      DemoRigFileText({"cam0", "cam1", "cam2"}, "udpm://239.255.76.67:7667?ttl=0", auth);
  const RigFile rig = ParseRigFile(text, "rig_hosts.yaml");
  EXPECT_EQ(CheckRig(rig), std::vector<std::string>{});
  ASSERT_EQ(rig.hosts.size(), 3u);
  EXPECT_EQ(rig.rig_network, kDemoRigNetworkUrl);
  EXPECT_FALSE(rig.insecure);
  // Every host holds the run's key.
  for (const RigHost& host : rig.hosts) {
    EXPECT_EQ(host.keys, std::vector<std::string>{"/tmp/demo/setup/rig.key"}) << host.name;
  }
  // Insecure, it names no key and says so.
  AuthOptions insecure;
  insecure.insecure = true;
  const RigFile open_rig = ParseRigFile(
      DemoRigFileText({"cam0"}, "udpm://239.255.76.67:7667?ttl=0", insecure), "rig_hosts.yaml");
  EXPECT_TRUE(open_rig.insecure);
  EXPECT_TRUE(open_rig.hosts[0].keys.empty());
  // Every program it names is placed on the host the file names.
  for (const RigHost& host : rig.hosts) {
    for (const RigProgram& program : host.programs) {
      EXPECT_EQ(DemoHostOf(program.program), host.name) << program.program;
    }
  }
}

TEST(DemoHostsTest, EveryProgramOfThePlanHasItsHost) {
  EXPECT_EQ(DemoHostOf("rig-sim-backdrop"), kCameraHostName);
  EXPECT_EQ(DemoHostOf("capture-background"), kCameraHostName);
  EXPECT_EQ(DemoHostOf("controller-closed_loop"), kControlHostName);
  EXPECT_EQ(DemoHostOf("lcm-logger"), kOperatorHostName);
  EXPECT_EQ(DemoHostOf("attacker"), kOperatorHostName);
  EXPECT_THROW(DemoHostOf("unknown"), std::invalid_argument);
}

std::vector<ExperimentTarget> Targets(int count, double hold_s) {
  std::vector<ExperimentTarget> targets;
  targets.reserve(static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) targets.push_back({1.0 + i * hold_s, 1.0 + (i + 1) * hold_s, {}});
  return targets;
}

TEST(ExperimentFaultsTest, TheStandardFaultsFitFiveSecondHoldsAndBadOnesAreNamed) {
  EXPECT_EQ(CheckFaults(StandardFaults(4), Targets(4, 5.0)), "");
  EXPECT_EQ(StandardFaults(2).size(), 1u);
  EXPECT_NE(CheckFaults(StandardFaults(4), Targets(4, 3.0)).find("control_link_down"),
            std::string::npos);
  EXPECT_NE(
      CheckFaults({{FaultKind::kKillShape, 7, 1.0, 0.0}}, Targets(4, 5.0)).find("no target 7"),
      std::string::npos);
}

TEST(ExperimentFaultsTest, TheInjectorMakesEachFaultOnceAtItsTimeAndBringsTheLinkBack) {
  std::vector<std::string> deeds;
  FaultInjector injector(StandardFaults(4),
                         {[&](bool up) { deeds.push_back(up ? "link up" : "link down"); },
                          [&] { deeds.push_back("kill"); },
                          [&] {
                            deeds.push_back("logger");
                            return int64_t{17'000'100};
                          }});
  const std::vector<ExperimentTarget> targets = Targets(4, 5.0);
  // Target 2 starts at 6 s: the link goes down at 7 s, for 2 s.
  for (double t = 0.0; t < 21.0; t += 0.01) {
    injector.Step(t, targets, static_cast<int64_t>(t * 1e6));
  }
  injector.Finish(21'000'000);
  EXPECT_EQ(deeds, (std::vector<std::string>{"link down", "link up", "kill", "logger"}));
  ASSERT_EQ(injector.events().size(), 3u);
  EXPECT_NEAR(static_cast<double>(injector.events()[0].start_utime) * 1e-6, 7.0, 0.02);
  EXPECT_NEAR(static_cast<double>(injector.events()[0].end_utime) * 1e-6, 9.0, 0.02);
  EXPECT_NEAR(static_cast<double>(injector.events()[1].start_utime) * 1e-6, 12.0, 0.02);
  EXPECT_EQ(injector.events()[2].end_utime, 17'000'100);
}

TEST(ExperimentFaultsTest, ALinkStillDownAtTheEndIsBroughtBack) {
  std::vector<bool> link;
  FaultInjector injector({{FaultKind::kControlLinkDown, 1, 0.0, 2.0}},
                         {[&](bool up) { link.push_back(up); }, [] {}, [] { return int64_t{0}; }});
  injector.Step(1.0, Targets(1, 5.0), 1'000'000);
  injector.Finish(1'500'000);
  EXPECT_EQ(link, (std::vector<bool>{false, true}));
  EXPECT_EQ(injector.events().at(0).end_utime, 1'500'000);
}

// Steps of 0.1 s from 0 to 3 s: fresh, held from 1.2 s, stopped from 2 s,
// moving again at 2.5 s; one command sent on stale sensing at 1.5 s.
std::string StepsCsv() {
  std::string csv = "time_s,utime,mode,sent,sensed_trigger_seq,sensing_age_s,note\n";
  for (int i = 0; i <= 30; ++i) {
    const double t = i * 0.1;
    std::string mode = "closed_loop";
    bool sent = true;
    double age = 0.05;
    if (i >= 12 && i < 20) mode = "hold", sent = false, age = 0.2 + (i - 12) * 0.1;
    if (i >= 20 && i < 25) mode = "stop", sent = false, age = 1.0 + (i - 20) * 0.1;
    if (i == 15) mode = "closed_loop", sent = true;
    csv += std::to_string(t) + "," + std::to_string(i * 100'000) + "," + mode + "," +
           (sent ? "1" : "0") + ",7," + std::to_string(age) + ",\n";
  }
  return csv + "3.1,3100000,clo";  // cut short by a kill
}

TEST(ExperimentFaultsTest, TheControllersConductIsReadFromItsSteps) {
  const std::vector<ControllerStep> steps = ParseControllerSteps(StepsCsv(), "steps.csv");
  ASSERT_EQ(steps.size(), 31u);
  const FaultEvent event{{FaultKind::kControlLinkDown, 1, 1.0, 1.3}, 1'000'000, 2'300'000};
  const ControllerConduct conduct = JudgeConduct(steps, event, 3'000'000, 0.2);
  EXPECT_EQ(conduct.steps, 21);
  EXPECT_EQ(conduct.held_steps, 7);
  EXPECT_EQ(conduct.stopped_steps, 5);
  EXPECT_EQ(conduct.sent_on_stale, 1);
  EXPECT_NEAR(conduct.first_hold_after_s, 0.2, 1e-9);
  EXPECT_NEAR(conduct.first_stop_after_s, 1.0, 1e-9);
  EXPECT_NEAR(conduct.resumed_after_s, 0.2, 1e-9);  // at 2.5 s, the link back at 2.3 s
  EXPECT_NEAR(conduct.max_sensing_age_s, 1.4, 1e-9);
  EXPECT_THROW(ParseControllerSteps("time_s,mode\n", "old.csv"), InputError);
}

TEST(ExperimentFaultsTest, TheLogsGapIsCountedAndALossWhileLoggingIsFound) {
  const LogContinuity whole = JudgeContinuity({{1, 2, 3, 4}, {9, 10, 11}});
  EXPECT_EQ(whole.messages, 7);
  EXPECT_EQ(whole.missing_within_runs, 0);
  EXPECT_EQ(whole.gap_between_runs, 4);
  const LogContinuity lossy = JudgeContinuity({{1, 2, 5}, {}, {6, 8}});
  EXPECT_EQ(lossy.missing_within_runs, 3);
  EXPECT_EQ(lossy.gap_between_runs, 0);
}

TEST(ExperimentFaultsTest, OneLogIsSplitIntoTheLoggersRunsAtItsRestarts) {
  const std::vector<std::pair<int64_t, int64_t>> logged = {{100, 1}, {200, 2}, {300, 3},
                                                           {700, 8}, {800, 9}, {1200, 14}};
  const auto segments = SplitAt(logged, {500, 1000});
  EXPECT_EQ(segments, (std::vector<std::vector<int64_t>>{{1, 2, 3}, {8, 9}, {14}}));
  const LogContinuity continuity = JudgeContinuity(segments);
  EXPECT_EQ(continuity.gap_between_runs, 4 + 4);
  EXPECT_EQ(continuity.missing_within_runs, 0);
}

TEST(ExperimentFaultsTest, TheOutageIsTheGapAcrossTheFault) {
  const std::vector<int64_t> times = {0, 33'000, 66'000, 900'000, 933'000};
  EXPECT_NEAR(OutageAround(times, 70'000), 0.834, 1e-9);
  EXPECT_EQ(OutageAround(times, 2'000'000), 0.0);
}

}  // namespace
}  // namespace shapesense
