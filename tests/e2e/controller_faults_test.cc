// The controller's faults end to end, inside this test's private network
// namespace (tests/support): the live pipeline with the rig-sim in plant
// mode, as `shapesense demo` runs it (MakeDemoPlan), and
// shapesense-controller in closed loop with its targets streamed. In turn:
//   - malformed and unreachable targets are rejected with a reason, and the
//     controller goes on;
//   - the sensing stops mid-move (the shape service frozen with SIGSTOP):
//     no tendon moves once the sensing is older than the watchdog's hold
//     age, and the controller stops once it is lost;
//   - the actuator link is cut (the rig-sim, which is the plant, killed):
//     the controller stops with an error naming the lost link.
#include <gtest/gtest.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <sstream>
#include <thread>

#include "clients/tools/demo/demo_plan.h"
#include "clients/tools/demo/demo_session.h"
#include "libs/sim/scene_generators.h"
#include "runtime/lcm/channels.h"
#include "runtime/process/process_group.h"
#include "services/controller/controller_config.h"
#include "shapesense/configuration_target_t.hpp"
#include "shapesense/tendon_command_t.hpp"
#include "tests/e2e/live_pipeline.h"
#include "tests/support/network_test.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using std::chrono::seconds;

struct Command {
  int64_t utime = 0;  // the controller's step
  std::vector<double> displacements;
  int8_t mode = 0;
};

// What the test hears: the controller's commands, the sensed shapes.
struct Heard {
  std::vector<Command> commands;
  std::vector<int64_t> shape_triggers;  // trigger times of shapes with q
  std::set<std::string> statuses;
};

class ControllerFaultsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(nettest::PrivateNetworkError(), "");
    out_ = fs::path(::testing::TempDir()) / ("controller_faults_" + std::to_string(getpid()));
    fs::remove_all(out_);
    config_ = fs::path(SHAPESENSE_SOURCE_DIR) / "config";
    settings_.bin_dir = E2E_BIN_DIR;
    settings_.lcm_logger = "/usr/bin/lcm-logger";
    settings_.out = out_;
    settings_.rate_hz = e2e::LiveRate();
    settings_.duration_s = 120.0;
    settings_.plant_config = config_ / "rig_plant.yaml";
    settings_.shape_config = config_ / "shape_service_plant.yaml";
    settings_.log_channels = kControlChannels;
    SyntheticRigOptions rig_options;
    rig_options.seed = settings_.seed;
    rig_ = MakeSyntheticRig(rig_options);
    for (const Camera& camera : rig_.cameras) settings_.camera_names.push_back(camera.name);
    plan_ = MakeDemoPlan(settings_);
    PrepareOutput(plan_, rig_);
    processes_ = std::make_unique<ProcessGroup>(
        plan_.logs_dir, stop_,
        ProcessGroup::Hooks{[this](int ms) { Pump(bus_, ms); },
                            [this](const std::string& s) { return heard_.statuses.contains(s); }});
    Listen();
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(out_);
  }

  void Listen() {
    bus_.Subscribe<tendon_command_t>(
        channels::kTendonCommand, [this](tendon_command_t&& command, const std::string&, int64_t) {
          heard_.commands.push_back({command.header.utime, command.displacement_mm, command.mode});
        });
    bus_.Subscribe<shape_t>(channels::kShape, [this](shape_t&& shape, const std::string&, int64_t) {
      if (shape.has_configuration) heard_.shape_triggers.push_back(shape.trigger_utime);
    });
    bus_.Subscribe<service_status_t>(
        channels::kStatusPattern, [this](service_status_t&& status, const std::string&, int64_t) {
          heard_.statuses.insert(status.service);
        });
  }

  // Lets the bus work for `s` seconds; throws ProgramFailure when a program ended.
  void Wait(double s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(s);
    while (std::chrono::steady_clock::now() < end) {
      Pump(bus_, 20);
      processes_->ReadOutput();
    }
  }

  std::string ControllerLog() const {
    std::ifstream file(plan_.logs_dir / "controller-closed_loop.log");
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
  }

  configuration_target_t Target(const Configuration& q) const {
    configuration_target_t target{};
    target.header.utime = NowUtime();
    target.kind = configuration_target_t::KIND_CONFIGURATION;
    for (int i = 0; i < 4; ++i) target.q[i] = q(i);
    target.source = "controller_faults_test";
    return target;
  }

  fs::path out_, config_;
  DemoSettings settings_;
  Rig rig_;
  DemoPlan plan_;
  LcmBus bus_{kDemoLcmUrl};
  Heard heard_;
  std::atomic<bool> stop_{false};
  std::unique_ptr<ProcessGroup> processes_;  // made in SetUp, once out_ is known
};

// The last command at or before `utime`.
const Command* CommandAt(const std::vector<Command>& commands, int64_t utime) {
  const Command* found = nullptr;
  for (const Command& command : commands) {
    if (command.utime <= utime) found = &command;
  }
  return found;
}

TEST_F(ControllerFaultsTest, BadTargetsLostSensingAndACutLinkAreHandledSafely) {
  std::ostringstream log;
  ASSERT_TRUE(StartAll(*processes_, plan_.background, log));
  processes_->StopAll();
  ASSERT_TRUE(StartAll(*processes_, plan_.pipeline, log)) << log.str();
  const ProgramSpec controller = ControllerRun(settings_, config_ / "controller_client.yaml",
                                               "closed_loop", out_ / "closed_loop");
  ASSERT_TRUE(processes_->Start(controller, kDemoStartTimeout));
  Wait(1.0);

  // Malformed and unreachable targets: garbage bytes, q not a number, a bend
  // far past the workspace, an unknown kind.
  lcm::LCM raw(kDemoLcmUrl);
  const char garbage[] = "not a configuration_target_t";
  raw.publish(channels::kTarget, garbage, sizeof(garbage));
  configuration_target_t not_a_number = Target(Configuration(0.0, 0.0, 0.0, 0.003));
  not_a_number.q[0] = std::nan("");
  bus_.Publish(channels::kTarget, not_a_number);
  bus_.Publish(channels::kTarget, Target(Configuration(0.05, 0.0, 0.0, 0.003)));
  configuration_target_t unknown_kind = Target(Configuration(0.0, 0.0, 0.0, 0.003));
  unknown_kind.kind = 9;
  bus_.Publish(channels::kTarget, unknown_kind);
  Wait(1.0);
  const std::string after_bad_targets = ControllerLog();
  size_t rejections = 0;
  for (size_t at = after_bad_targets.find("target rejected: "); at != std::string::npos;
       at = after_bad_targets.find("target rejected: ", at + 1)) {
    ++rejections;
  }
  EXPECT_EQ(rejections, 3u) << after_bad_targets;
  EXPECT_NE(after_bad_targets.find("message rejected: SHAPESENSE_TARGET"), std::string::npos)
      << after_bad_targets;

  // A long move (a bend of 1 rad at 2 mm/s of tendon), then the sensing
  // stops in the middle of it.
  const int64_t move_start = NowUtime();
  bus_.Publish(channels::kTarget, Target(Configuration(0.0, 0.00625, 0.0, 0.004)));
  Wait(0.6);
  const int64_t frozen_at = NowUtime();
  processes_->Signal("shape", SIGSTOP);
  Wait(2.5);
  processes_->Signal("shape", SIGCONT);
  Wait(0.5);

  // The watchdog, from the trigger of the last sensed shape.
  const ControllerSetup setup = LoadControllerSetup(config_ / "controller_client.yaml");
  const WatchdogOptions& watchdog = setup.controller.watchdog;
  int64_t last_sensed = 0;
  for (const int64_t trigger : heard_.shape_triggers) {
    if (trigger <= frozen_at) last_sensed = std::max(last_sensed, trigger);
  }
  ASSERT_GT(last_sensed, move_start) << "sensing during the move";
  const Command* at_freeze = CommandAt(heard_.commands, last_sensed);
  const Command* before_move = CommandAt(heard_.commands, move_start);
  ASSERT_NE(at_freeze, nullptr);
  ASSERT_NE(before_move, nullptr);
  EXPECT_NE(at_freeze->displacements, before_move->displacements) << "it was moving";
  const int64_t hold_by = last_sensed + static_cast<int64_t>((watchdog.hold_age + 0.02) * 1e6);
  const Command* held = CommandAt(heard_.commands, hold_by);
  ASSERT_NE(held, nullptr);
  bool stopped = false;
  for (const Command& command : heard_.commands) {
    if (command.utime <= hold_by || command.utime > frozen_at + 2'500'000) continue;
    EXPECT_EQ(command.displacements, held->displacements)
        << "a tendon moved " << (command.utime - last_sensed) * 1e-6
        << " s after the last sensed shape";
    stopped = stopped || command.mode == tendon_command_t::MODE_STOP;
  }
  EXPECT_TRUE(stopped) << "sensing lost for longer than " << watchdog.lost_age << " s: a stop";

  // The actuator link cut: the plant falls silent.
  processes_->Signal("rig-sim", SIGKILL);
  const auto deadline = std::chrono::steady_clock::now() + seconds(5);
  while (processes_->IsRunning(controller.name) && std::chrono::steady_clock::now() < deadline) {
    Wait(0.1);
  }
  const ProgramEnd end = processes_->Stop(controller.name);
  EXPECT_EQ(end.how, "exited with status 1") << "the controller stops with an error";
  EXPECT_NE(ControllerLog().find("link lost: no plant state"), std::string::npos)
      << ControllerLog();
  processes_->StopAll();
}

}  // namespace
}  // namespace shapesense
