#include "tests/services/controller/in_process_rig.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <random>

#include "libs/control/safety_gate.h"
#include "libs/core/error.h"
#include "runtime/file_io.h"
#include "shapesense/tendon_state_t.hpp"

namespace shapesense::testing {
namespace fs = std::filesystem;

// The rig's marker to itself, on a channel nobody else uses.
constexpr const char* kBarrierChannel = "TEST_IN_PROCESS_RIG_BARRIER";

ManipulatorOptions CatheterModel() {
  return ParseManipulatorYaml(
      ReadTextFile(fs::path(SHAPESENSE_SOURCE_DIR) / "config/manipulator.yaml"),
      "manipulator.yaml");
}

TendonPlantOptions OffNominalPlant() {
  TendonPlantOptions plant;
  plant.stiffness_factor = {1.2, 0.8, 0.8, 1.2, 0.8};
  plant.tendon_play = 0.15;
  plant.tendon_play_spread = 0.3;
  plant.seed = 7;
  return plant;
}

Configuration ResolvedConfiguration(const ControllerSetup& setup, double kappa_x, double kappa_z,
                                    double eps1) {
  Target target;
  target.configuration = Configuration(kappa_x, kappa_z, 0.0, eps1);
  const TendonModel model(setup.manipulator);
  const ResolvedTarget resolved = TargetResolver(model, setup.controller).Resolve(target);
  EXPECT_TRUE(resolved.ok) << resolved.reason;
  return resolved.configuration;
}

fs::path TestLogDir() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = fs::path(::testing::TempDir()) / "shapesense_controller" /
                 (std::string(info->test_suite_name()) + "." + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

static ControllerSetup BaseSetup(ControlMode mode, const fs::path& log_dir) {
  ControllerSetup setup;
  setup.source = "test";
  setup.manipulator = CatheterModel();
  setup.controller.mode = ControlModeName(mode);
  setup.actuators.driver = "rig";
  setup.actuators.tendons = static_cast<int>(setup.manipulator.tendons.size());
  setup.client.log.csv = (log_dir / "controller.csv").string();
  setup.client.log.lcm = (log_dir / "controller.lcmlog").string();
  setup.client.progress_period_s = 0.0;
  return setup;
}

ControllerSetup TrajectorySetup(ControlMode mode, const std::vector<Target>& targets,
                                const fs::path& log_dir) {
  ControllerSetup setup = BaseSetup(mode, log_dir);
  Trajectory trajectory;
  trajectory.interpolate = false;
  trajectory.targets = targets;
  const TendonModel model(setup.manipulator);
  setup.trajectory =
      ResolveTrajectory(trajectory, TargetResolver(model, setup.controller), "test targets");
  return setup;
}

ControllerSetup StreamSetup(ControlMode mode, const fs::path& log_dir) {
  ControllerSetup setup = BaseSetup(mode, log_dir);
  setup.client.targets = "stream";
  return setup;
}

static Eigen::VectorXd StartOf(const ControllerSetup& setup, const Eigen::VectorXd& initial) {
  if (initial.size() > 0) return initial;
  return SafetyEnvelope(TendonModel(setup.manipulator), setup.controller.limits).RestingCommand();
}

static LcmBusOptions Memq() {
  LcmBusOptions options;
  options.url = "memq://";
  return options;
}

InProcessRig::InProcessRig(const ControllerSetup& setup, const FakeRigOptions& rig,
                           const Eigen::VectorXd& initial)
    : InProcessRig(setup, rig, Memq(), initial) {}

InProcessRig::InProcessRig(const ControllerSetup& setup, const FakeRigOptions& rig,
                           const LcmBusOptions& bus_options, const Eigen::VectorXd& initial)
    : setup_(setup),
      period_us_(static_cast<int64_t>(std::llround(1e6 / setup.controller.loop_rate))),
      bus_(bus_options),
      barriers_(bus_options.url.rfind("udpm://", 0) == 0),
      plant_(
          bus_, setup.manipulator, rig, [this] { return now_; }, StartOf(setup, initial)),
      driver_(bus_, setup.actuators.tendons, setup.actuators.rig, [this] { return now_; }),
      log_(setup.client.log.csv, setup.client.log.lcm, setup.actuators.tendons),
      client_(
          setup_, bus_, driver_, log_, [this] { return now_; }, &progress_) {}

void InProcessRig::HandOver() {
  if (!barriers_) return client_.DrainBus();
  if (barrier_sent_ == 0) {
    barrier_id_ = static_cast<int64_t>(std::random_device{}()) << 20 | getpid();
    bus_.Subscribe<tendon_state_t>(kBarrierChannel,
                                   [this](tendon_state_t&& marker, const std::string&, int64_t) {
                                     if (marker.header.data_age_us == barrier_id_)
                                       barrier_seen_ = marker.header.seq;
                                   });
  }
  tendon_state_t marker{};
  marker.header.data_age_us = barrier_id_;
  marker.header.seq = ++barrier_sent_;
  ASSERT_TRUE(bus_.Publish(kBarrierChannel, marker));
  for (int i = 0; i < 500 && barrier_seen_ < barrier_sent_; ++i) client_.HandleBus(10);
  ASSERT_EQ(barrier_seen_, barrier_sent_) << "the barrier did not come back within 5 s";
}

void InProcessRig::Start() {
  plant_.Tick();
  client_.Start();  // the driver's Connect waits for the plant's state itself
  start_utime_ = now_;
}

void InProcessRig::Step() {
  now_ += period_us_;
  plant_.Tick();
  HandOver();
  client_.Step();
}

void InProcessRig::RunFor(double seconds, const std::function<void(const StepRecord&)>& each) {
  const int64_t steps = std::llround(seconds * 1e6 / static_cast<double>(period_us_));
  for (int64_t i = 0; i < steps && !client_.finished(); ++i) {
    Step();
    if (each) each(client_.last_step());
  }
}

}  // namespace shapesense::testing
