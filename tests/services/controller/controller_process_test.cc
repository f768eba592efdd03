// The real shapesense-controller program in a private network namespace,
// over LCM multicast, against the fake plant peer running in this process:
// SIGTERM stops it cleanly (exit 0) with both logs complete and readable;
// a plant that goes silent ends it with exit 1 and an error naming the
// driver, the logs complete up to that point.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <atomic>
#include <csignal>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <thread>

#include "libs/control/safety_gate.h"
#include "runtime/devices/device_clock.h"
#include "runtime/lcm/channels.h"
#include "runtime/process/child_process.h"
#include "tests/services/controller/controller_log_check.h"
#include "tests/services/controller/in_process_rig.h"
#include "tests/support/network_test.h"

namespace shapesense {
namespace {
namespace fs = std::filesystem;
using std::chrono::milliseconds;
using ::testing::HasSubstr;

const char* const kUrl = "udpm://239.255.76.67:7667?ttl=0";
const fs::path kConfigDir = fs::path(SHAPESENSE_SOURCE_DIR) / "config";

// The fake plant peer on its own thread and bus, on the host clock, ticking at 100 Hz.
class PlantPeer {
 public:
  PlantPeer() : thread_([this] { Run(); }) {}
  ~PlantPeer() { Stop(); }
  void Stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }

 private:
  void Run() {
    LcmBus bus(kUrl);
    const ManipulatorOptions model = testing::CatheterModel();
    testing::FakeRigOptions options;
    options.plant = testing::OffNominalPlant();
    const Eigen::VectorXd rest =
        SafetyEnvelope(TendonModel(model), SafetyLimits{}).RestingCommand();
    testing::FakeRigPlant plant(bus, model, options, EpochMicros, rest);
    auto next = std::chrono::steady_clock::now();
    while (!stop_.load()) {
      next += milliseconds(10);
      while (std::chrono::steady_clock::now() < next) bus.Handle(2);
      plant.Tick();
    }
  }

  std::atomic<bool> stop_{false};
  std::thread thread_;
};

struct RunFiles {
  fs::path dir;
  fs::path config;
  fs::path csv;
  fs::path lcm;
};

RunFiles WriteConfig() {
  RunFiles run;
  run.dir = testing::TestLogDir();
  run.csv = run.dir / "controller.csv";
  run.lcm = run.dir / "controller.lcmlog";
  std::ofstream(run.dir / "targets.yaml")
      << "targets:\n  - {time: 0, q: [0, 0, 0, 0.0015]}\n"
         "  - {time: 1, q: [0.003, 0, 0, 0.003]}\n  - {time: 2, q: [0, 0.003, 0, 0.003]}\n";
  run.config = run.dir / "client.yaml";
  std::ofstream(run.config) << "controller: " << (kConfigDir / "controller.yaml").string()
                            << "\nactuators: " << (kConfigDir / "actuators.yaml").string()
                            << "\ndriver: rig\nmanipulator: "
                            << (kConfigDir / "manipulator.yaml").string()
                            << "\ntargets: targets.yaml\nlcm_url: \"" << kUrl
                            << "\"\nlog: {csv: controller.csv, lcm: controller.lcmlog}\n"
                               "progress_period_s: 0.5\n";
  return run;
}

ChildOptions Options() {
  ChildOptions options;
  options.capture_stderr = true;
  options.end_with_parent = true;
  return options;
}

// Both logs complete: one row, one command and one state event per step,
// every command within the limits. Returns the rows.
testing::ControllerCsv ExpectLogsComplete(const RunFiles& run) {
  testing::ControllerCsv csv = testing::ReadControllerCsv(run.csv);
  EXPECT_EQ(csv.bad_rows, 0);
  EXPECT_GT(csv.rows.size(), 50u);
  const testing::LimitCheck check = testing::CheckLoggedCommands(
      csv, TendonModel(testing::CatheterModel()), ControllerOptions{}.limits);
  EXPECT_EQ(check.total(), 0) << check.first;
  EXPECT_EQ(check.below_floor, 0);
  lcm::LogFile log(run.lcm.string(), "r");
  EXPECT_TRUE(log.good());
  std::map<std::string, size_t> events;
  while (const lcm::LogEvent* event = log.readNextEvent()) ++events[event->channel];
  EXPECT_EQ(events[channels::kTendonCommand], csv.rows.size());
  EXPECT_EQ(events[channels::kTendonState], csv.rows.size());
  EXPECT_GT(events[channels::kShape], 10u);
  return csv;
}

TEST(ControllerProcessTest, SigtermStopsCleanlyWithCompleteLogs) {
  ASSERT_EQ(nettest::PrivateNetworkError(), "");
  const RunFiles run = WriteConfig();
  PlantPeer plant;
  ChildProcess controller({CONTROLLER_BINARY, "--config", run.config.string()}, Options());
  ASSERT_TRUE(controller.WaitForLine("running:", milliseconds(20000))) << controller.Tail(20);
  ASSERT_TRUE(controller.WaitForLine(": moving", milliseconds(20000))) << controller.Tail(20);
  for (int progress = 0; progress < 3; ++progress) {  // lines at 0, 0.5 and 1 s of control
    ASSERT_TRUE(controller.WaitForLine(" commands, ", milliseconds(20000))) << controller.Tail(20);
  }
  const int status = controller.Stop(SIGTERM, milliseconds(10000));
  plant.Stop();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << DescribeExitStatus(status) << "\n"
                                                             << controller.Tail(20);
  EXPECT_THAT(controller.output(), HasSubstr("stopping: SIGINT or SIGTERM"));
  const testing::ControllerCsv csv = ExpectLogsComplete(run);
  ASSERT_FALSE(csv.rows.empty());
  EXPECT_EQ(csv.Text(csv.rows.size() - 1, "mode"), "stop");
  EXPECT_THAT(controller.output(),
              HasSubstr("logged " + std::to_string(csv.rows.size()) + " rows"));
  std::printf("%s\n", controller.Tail(12).c_str());
}

TEST(ControllerProcessTest, APlantThatFallsSilentEndsTheRunWithAClearError) {
  ASSERT_EQ(nettest::PrivateNetworkError(), "");
  const RunFiles run = WriteConfig();
  PlantPeer plant;
  ChildProcess controller({CONTROLLER_BINARY, "--config", run.config.string()}, Options());
  ASSERT_TRUE(controller.WaitForLine(": moving", milliseconds(20000))) << controller.Tail(20);
  for (int progress = 0; progress < 3; ++progress) {  // lines at 0, 0.5 and 1 s of control
    ASSERT_TRUE(controller.WaitForLine(" commands, ", milliseconds(20000))) << controller.Tail(20);
  }
  plant.Stop();
  EXPECT_TRUE(controller.WaitForLine(
      "failed: actuators (rig plant over LCM) failed: rig: link lost: no plant state",
      milliseconds(10000)))
      << controller.Tail(20);
  const int status = controller.Stop(SIGTERM, milliseconds(10000));
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << DescribeExitStatus(status) << "\n"
                                                             << controller.Tail(20);
  const testing::ControllerCsv csv = ExpectLogsComplete(run);
  ASSERT_FALSE(csv.rows.empty());
  EXPECT_THAT(csv.Text(csv.rows.size() - 1, "note"), HasSubstr("link lost"));
  std::printf("%s\n", controller.Tail(12).c_str());
}

}  // namespace
}  // namespace shapesense
