// The virtual rig's plant mode (plant_world.h): the example config loads and
// fits the default synthetic rig; commands move the plant exactly as the
// tendon plant itself; the scene and its truth are the plant's (centreline,
// tip, q); malformed commands are rejected with a reason and change nothing;
// the actuators' speed, stop, watchdog and stall; the state over LCM
// memq:// at its rate; and the controller's own rig driver against it.
#include "services/rig_sim/plant_world.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "libs/config/options_yaml.h"
#include "libs/core/error.h"
#include "libs/geometry/polyline.h"
#include "libs/mechanics/configuration_geometry.h"
#include "libs/sim/scene_generators.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/shape_message.h"
#include "services/controller/rig_plant_driver.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

constexpr int64_t kStart = 1'700'000'000'000'000;
constexpr int64_t kMs = 1000;

const fs::path kExample = fs::path(SHAPESENSE_SOURCE_DIR) / "config" / "rig_plant.yaml";

// The example config with the actuators starting at 0 (the file starts them
// taut), which the tests' reference plants and expected positions assume.
const PlantWorldSetup& Example() {
  static const PlantWorldSetup setup = [] {
    PlantWorldSetup loaded = LoadPlantWorldSetup(kExample);
    loaded.options.initial_displacements.clear();
    return loaded;
  }();
  return setup;
}

tendon_command_t Command(const Eigen::VectorXd& y, int8_t mode = tendon_command_t::MODE_OPEN_LOOP) {
  tendon_command_t command{};
  command.num_tendons = static_cast<int32_t>(y.size());
  command.displacement_mm.assign(y.data(), y.data() + y.size());
  command.source_trigger_seq = -1;
  command.mode = mode;
  return command;
}

// Displacements the controller's gate could send: its default range.
Eigen::VectorXd RandomCommand(std::mt19937& rng, int tendons) {
  std::uniform_real_distribution<double> mm(-1.0, 6.5);
  Eigen::VectorXd y(tendons);
  for (int i = 0; i < tendons; ++i) y(i) = mm(rng);
  return y;
}

double Farthest(const Polyline& points, const Polyline& from) {
  const std::vector<double> arc = CumulativeArcLength(from);
  double farthest = 0.0;
  for (const Vec3& p : points) {
    farthest = std::max(farthest, ClosestPointOnPolyline(from, arc, p).distance);
  }
  return farthest;
}

fs::path WriteTemp(const std::string& name, const std::string& text) {
  fs::path path = fs::temp_directory_path() / ("plant_world_test_" + name);
  std::ofstream(path) << text;
  return path;
}

std::string LoadError(const std::string& yaml) {
  const fs::path path = WriteTemp(
      "bad.yaml", "manipulator: " + kExample.parent_path().string() + "/manipulator.yaml\n" + yaml);
  try {
    LoadPlantWorldSetup(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

TEST(PlantWorldOptions, TheExampleConfigLoadsDocumentsEveryKeyAndFitsTheSyntheticRig) {
  const PlantWorldSetup setup = LoadPlantWorldSetup(kExample);
  EXPECT_EQ(setup.model.tendons.size(), 4u);
  EXPECT_EQ(setup.options.initial_displacements.size(), 4u) << "the actuators start taut";
  EXPECT_TRUE(fs::exists(setup.options.manipulator)) << "resolved against the config's folder";
  // The file is its own values, each under its documentation.
  const std::string text = ReadTextFile(kExample);
  const auto as_written = OptionsFromYamlText<PlantWorldOptions>(text, kExample.string());
  EXPECT_THAT(text, HasSubstr(OptionsToDocumentedYaml(as_written)));
  // Straight and bent as far as the controller's workspace allows (2 rad),
  // the body is inside the default synthetic rig's workspace.
  const Rig rig = MakeSyntheticRig(SyntheticRigOptions{});
  const PlantWorld world(setup);
  const Pose3& world_from_base = world.world_from_base();
  for (const Configuration& q : {Configuration(0, 0, 0, 0), Configuration(0.0125, 0, 0, 0.01),
                                 Configuration(0, -0.0125, 0, 0.01)}) {
    const TubeScene scene =
        SceneOfConfiguration(q, world.rest(), world_from_base, setup.options.scene);
    EXPECT_LT((scene.centerline.front() - rig.base_point).norm(), 1e-9)
        << "enters at the base point";
    // The body enters through the floor, the rest keeps a radius off every face.
    for (const Vec3& p : scene.centerline) {
      const Vec3 low = rig.workspace_min + Vec3(scene.radius, scene.radius, 0.0);
      const Vec3 high = rig.workspace_max - Vec3::Constant(scene.radius);
      EXPECT_TRUE((p.array() >= low.array()).all() && (p.array() <= high.array()).all())
          << p.transpose() << " for q " << q.transpose();
    }
  }
}

TEST(PlantWorldOptions, BadValuesNameTheFileAndTheKey) {
  EXPECT_THAT(LoadError("state_rate_hz: 0\n"), HasSubstr("bad.yaml: state_rate_hz: expected"));
  EXPECT_THAT(LoadError("initial_displacements: [1, 2]\n"),
              HasSubstr("initial_displacements: expected 4 (the model's tendons) or none, got 2"));
  EXPECT_THAT(LoadError("plant: {tendon_play: -1}\n"), HasSubstr("plant.tendon_play: expected"));
  EXPECT_THAT(LoadError("scene: {tapes: {distal_band_before_tip: 500}}\n"),
              HasSubstr("bad.yaml: scene.tapes.distal_band_before_tip"));
  EXPECT_THAT(LoadError("max_strain: 1.5\n"), HasSubstr("max_strain: expected"));
  EXPECT_THAT(LoadError("speed: 3\n"), HasSubstr("speed: unknown key"));
  EXPECT_THAT(LoadError("initial_displacements: [200, 200, 200, 200]\n"),
              HasSubstr("initial_displacements: the start is beyond max_strain or max_bend_angle"));
  const fs::path no_model = WriteTemp("no_model.yaml", "manipulator: nowhere.yaml\n");
  try {
    LoadPlantWorldSetup(no_model);
    ADD_FAILURE() << "a missing model file was accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr((no_model.parent_path() / "nowhere.yaml").string()));
  }
}

TEST(PlantWorld, CommandsMoveThePlantExactlyAsTheTendonPlant) {
  PlantWorldSetup setup = Example();
  setup.options.command_timeout_s = 0.0;  // moves of up to 7.5 mm at 10 mm/s
  std::mt19937 rng(7);
  for (int run = 0; run < 10; ++run) {
    PlantWorld world(setup);
    TendonPlant reference(setup.model, setup.options.plant, Eigen::VectorXd::Zero(4));
    int64_t now = kStart;
    for (int step = 0; step < 20; ++step) {
      const Eigen::VectorXd y = RandomCommand(rng, 4);
      now += 10 * kMs;
      ASSERT_EQ(world.OnCommand(Command(y), now), "");
      world.Advance(now + 2 * kMs);  // the actuators (10 mm/s) move at most 0.02 mm ...
      reference.Command(world.Snapshot().positions);
      EXPECT_EQ(world.Snapshot().configuration, reference.configuration());
      world.Advance(now + 2000 * kMs);  // ... and get there in time
      reference.Command(y);
      const PlantSnapshot snapshot = world.Snapshot();
      ASSERT_FALSE(snapshot.stalled);
      EXPECT_EQ(snapshot.positions, y);
      EXPECT_EQ(snapshot.configuration, reference.configuration());
      EXPECT_EQ(snapshot.tendon_displacements, reference.tendon_displacements());
      now += 2000 * kMs;
    }
  }
}

TEST(PlantWorld, PullingATendonBendsTowardIt) {
  PlantWorldOptions options = Example().options;
  options.actuator_speed = 0.0;
  options.plant.tendon_play = 0.0;  // the two x tendons' play would differ
  PlantWorld world(Example().model, options);
  // Tendon 1 sits at +z: pulled with the others taut, kappa_x > 0 (docs/mechanics.md).
  ASSERT_EQ(world.OnCommand(Command(Eigen::Vector4d(1.0, 4.0, 1.0, 1.0)), kStart), "");
  world.Advance(kStart);
  EXPECT_GT(world.Snapshot().configuration(kKappaX), 1e-4);
  EXPECT_NEAR(world.Snapshot().configuration(kKappaZ), 0.0, 1e-9);
}

TEST(PlantWorld, TheSceneAndItsTruthAreThePlants) {
  PlantWorldSetup setup = Example();
  setup.options.actuator_speed = 0.0;
  PlantWorld world(setup);
  TendonPlant reference(setup.model, setup.options.plant, Eigen::VectorXd::Zero(4));
  const Pose3 base_from_world = world.world_from_base().inverse();
  std::mt19937 rng(11);
  int64_t now = kStart;
  for (int i = 0; i < 12; ++i) {
    const Eigen::VectorXd y = RandomCommand(rng, 4);
    ASSERT_EQ(world.OnCommand(Command(y), now), "");
    now += 3000 * kMs;
    reference.Command(y);
    const TubeScene scene = world.SceneAtUtime(now);
    ASSERT_TRUE(scene.configuration.has_value());
    EXPECT_EQ(*scene.configuration, reference.configuration());
    // Every point of the scene on the plant's centreline; the tip the plant's.
    Polyline in_base;
    for (const Vec3& p : scene.centerline) in_base.push_back(base_from_world * p);
    EXPECT_LT(Farthest(in_base, reference.Centerline()), 1e-3);
    EXPECT_LT((in_base.back() - reference.BaseFromTip().translation()).norm(), 1e-9);
    EXPECT_EQ(scene.tapes.size(), 2u) << "the junction and distal bands are in view";

    const shape_t truth = world.TruthMessage(scene, i, now, i, now + kMs);
    EXPECT_TRUE(truth.valid);
    const std::optional<Configuration> q = MessageConfiguration(truth);
    ASSERT_TRUE(q.has_value());
    EXPECT_EQ(*q, reference.configuration());
    EXPECT_EQ(truth.configuration_residual_mm, 0.0);
    EXPECT_EQ(truth.num_markers, 2);
    // Straight (on the base's y axis, before the junction) or curved by |kappa|.
    const double kappa = std::hypot((*q)(kKappaX), (*q)(kKappaZ));
    const double junction = CompressedLengths(*q, world.rest()).proximal;
    for (int k = 0; k < truth.num_points; ++k) {
      const auto& c = truth.centerline[static_cast<size_t>(k)];
      const Vec3 p = base_from_world * Vec3(c[0], c[1], c[2]);
      const bool straight = p.y() < junction - 1e-6;
      EXPECT_EQ(truth.curvature[static_cast<size_t>(k)], straight ? 0.0 : kappa) << k;
    }
  }
}

TEST(PlantWorld, MalformedCommandsAreRejectedWithAReasonAndChangeNothing) {
  PlantWorld world(Example());
  ASSERT_EQ(world.OnCommand(Command(Eigen::Vector4d(1.0, 2.0, 1.5, 0.5)), kStart), "");
  world.Advance(kStart + 400 * kMs);  // there (10 mm/s), before the watchdog's 0.5 s
  const PlantSnapshot before = world.Snapshot();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  tendon_command_t mismatched = Command(Eigen::Vector4d(1, 1, 1, 1));
  mismatched.num_tendons = 5;
  const std::vector<std::pair<tendon_command_t, std::string>> cases = {
      {Command(Eigen::Vector3d(1, 1, 1)),
       "displacement_mm: expected 4 displacements (the plant's tendons), got 3"},
      {Command(Eigen::VectorXd::Ones(5)), "expected 4 displacements (the plant's tendons), got 5"},
      {Command(Eigen::Vector4d(1, nan, 1, 1)), "displacement_mm[1]: expected a finite number"},
      {Command(Eigen::Vector4d(1, 1, 1, -inf)), "displacement_mm[3]: expected a finite number"},
      {Command(Eigen::Vector4d(1, 1, 1, 1), 9),
       "mode: expected MODE_HOLD .. MODE_STOP (0-4), got 9"},
      {Command(Eigen::Vector4d(1, 1, 1, 1), -1), "got -1"},
      {mismatched, "num_tendons: 5 but 4 displacements"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    EXPECT_THAT(world.OnCommand(cases[i].first, kStart + 420 * kMs), HasSubstr(cases[i].second));
    world.Advance(kStart + 450 * kMs);
    const PlantSnapshot after = world.Snapshot();
    EXPECT_EQ(after.target, before.target);
    EXPECT_EQ(after.positions, before.positions);
    EXPECT_EQ(after.configuration, before.configuration);
    EXPECT_EQ(after.commands, before.commands);
    EXPECT_EQ(after.rejected, before.rejected + static_cast<int64_t>(i) + 1);
    EXPECT_THAT(after.last_rejection, HasSubstr(cases[i].second));
  }
  // A stop is never refused for what it carries.
  tendon_command_t stop = Command(Eigen::VectorXd(0), tendon_command_t::MODE_STOP);
  EXPECT_EQ(world.OnCommand(stop, kStart + 460 * kMs), "");
  EXPECT_EQ(world.Snapshot().stops, 1);
}

TEST(PlantWorld, ActuatorsMoveAtTheirSpeedAndStopOnAStopOrTheWatchdog) {
  PlantWorldOptions options = Example().options;
  options.actuator_speed = 2.0;  // mm/s
  options.command_timeout_s = 0.5;
  options.plant.tendon_play = 0.0;
  PlantWorld world(Example().model, options);
  TendonPlant reference(Example().model, options.plant, Eigen::VectorXd::Zero(4));
  const Eigen::Vector4d unit(1.0, 0.0, 0.0, 0.0);
  ASSERT_EQ(world.OnCommand(Command(unit), kStart), "");
  world.Advance(kStart + 250 * kMs);
  EXPECT_NEAR(world.Snapshot().positions(0), 0.5, 1e-12);
  const Configuration halfway = world.Snapshot().configuration;
  world.Advance(kStart + 400 * kMs);
  EXPECT_NEAR(world.Snapshot().positions(0), 0.8, 1e-12);
  // The past is remembered: the scene of 250 ms is the halfway configuration.
  EXPECT_EQ(world.ConfigurationAtUtime(kStart + 300 * kMs), halfway);
  EXPECT_EQ(*world.SceneAtUtime(kStart + 250 * kMs).configuration, halfway);
  world.Advance(kStart + 500 * kMs);
  EXPECT_EQ(world.Snapshot().positions, unit);

  // Toward 3 mm from 1 mm, but no command after it: the watchdog stops the
  // actuators 0.5 s on, at 2 mm.
  const int64_t t1 = kStart + 1000 * kMs;
  ASSERT_EQ(world.OnCommand(Command(3.0 * unit), t1), "");
  world.Advance(t1 + 2000 * kMs);
  PlantSnapshot snapshot = world.Snapshot();
  EXPECT_NEAR(snapshot.positions(0), 2.0, 1e-12);
  EXPECT_EQ(snapshot.target, snapshot.positions);
  EXPECT_EQ(snapshot.timeouts, 1);
  // A rejected command does not feed the watchdog either.
  const int64_t t2 = t1 + 3000 * kMs;
  ASSERT_EQ(world.OnCommand(Command(5.0 * unit), t2), "");
  EXPECT_NE(world.OnCommand(Command(Eigen::Vector3d(1, 1, 1)), t2 + 400 * kMs), "");
  world.Advance(t2 + 700 * kMs);
  EXPECT_NEAR(world.Snapshot().positions(0), 3.0, 1e-12) << "stopped at t2 + 0.5 s";
  // A stop mid-move holds where the actuators stand.
  const int64_t t3 = t2 + 1000 * kMs;
  ASSERT_EQ(world.OnCommand(Command(5.0 * unit), t3), "");
  world.Advance(t3 + 100 * kMs);
  ASSERT_EQ(world.OnCommand(Command(unit, tendon_command_t::MODE_STOP), t3 + 100 * kMs), "");
  world.Advance(t3 + 1000 * kMs);
  snapshot = world.Snapshot();
  EXPECT_NEAR(snapshot.positions(0), 3.2, 1e-12);
  EXPECT_EQ(snapshot.stops, 1);
  reference.Command(snapshot.positions);
  EXPECT_EQ(snapshot.configuration, reference.configuration());
}

TEST(PlantWorld, AMovePastTheLimitsStallsAndTheSceneStaysDrawable) {
  PlantWorldOptions options = Example().options;
  options.actuator_speed = 0.0;
  PlantWorld world(Example().model, options);
  const Eigen::Vector4d start(1.0, 1.0, 1.0, 1.0);
  ASSERT_EQ(world.OnCommand(Command(start), kStart), "");
  world.Advance(kStart);
  ASSERT_EQ(world.OnCommand(Command(Eigen::Vector4d::Constant(400.0)), kStart + 10 * kMs), "");
  const tendon_state_t state = world.State(kStart + 20 * kMs);
  EXPECT_TRUE(world.Snapshot().stalled);
  EXPECT_EQ(world.Snapshot().positions, start);
  for (const int32_t fault : state.fault) EXPECT_TRUE(fault & tendon_state_t::FAULT_LIMIT);
  EXPECT_NO_THROW(world.SceneAtUtime(kStart + 30 * kMs));
  // A stop ends it: the actuators stand where they are, nothing held back.
  ASSERT_EQ(world.OnCommand(Command(start, tendon_command_t::MODE_STOP), kStart + 40 * kMs), "");
  for (const int32_t fault : world.State(kStart + 50 * kMs).fault) {
    EXPECT_FALSE(fault & tendon_state_t::FAULT_LIMIT);
  }
}

TEST(PlantWorld, TheStateIsTheActuatorsTheTrueTensionsAndSlack) {
  PlantWorldSetup setup = Example();  // tendon play 0.15 mm +- 30%
  setup.options.actuator_speed = 0.0;
  PlantWorld world(setup);
  std::mt19937 rng(3);
  int64_t now = kStart;
  for (int i = 0; i < 20; ++i) {
    const Eigen::VectorXd y = RandomCommand(rng, 4);
    ASSERT_EQ(world.OnCommand(Command(y), now), "");
    now += 2000 * kMs;
    const tendon_state_t state = world.State(now);
    const PlantSnapshot snapshot = world.Snapshot();
    ASSERT_EQ(state.num_tendons, 4);
    EXPECT_EQ(state.header.utime, now);
    for (int k = 0; k < 4; ++k) {
      const auto index = static_cast<size_t>(k);
      // What an encoder reads: the actuator, not the tendon's far end.
      EXPECT_EQ(state.displacement_mm[index], y(k));
      EXPECT_LE(std::abs(snapshot.tendon_displacements(k) - y(k)), 0.15 * 1.3 / 2 + 1e-12);
      EXPECT_EQ(state.tension_n[index], snapshot.tensions(k));
      EXPECT_EQ((state.fault[index] & tendon_state_t::FAULT_SLACK) != 0, snapshot.tensions(k) <= 0);
    }
  }
  // At rest every tendon is slack.
  PlantWorld resting(setup);
  for (const int32_t fault : resting.State(kStart).fault)
    EXPECT_EQ(fault, tendon_state_t::FAULT_SLACK);
}

// ---- over LCM ------------------------------------------------------------------

class PlantLinkTest : public ::testing::Test {
 protected:
  PlantLinkTest() {
    bus_.Subscribe<tendon_state_t>(
        channels::kPlantState,
        [this](tendon_state_t&& state, const std::string&, int64_t) { states_.push_back(state); });
  }
  static PlantWorldOptions Options(double rate_hz) {
    PlantWorldOptions options = Example().options;
    options.state_rate_hz = rate_hz;
    options.actuator_speed = 0.0;
    return options;
  }
  void HandleAll() {
    while (bus_.Handle(0) > 0) {
    }
  }
  // `seconds` of 1 ms polls, every message handled.
  void Run(PlantLink& link, double seconds) {
    for (int i = 0; i < static_cast<int>(std::lround(seconds * 1000.0)); ++i) {
      HandleAll();
      last_poll_ = link.Poll(now_);
      rejections_.insert(rejections_.end(), last_poll_.rejections.begin(),
                         last_poll_.rejections.end());
      HandleAll();
      now_ += kMs;
    }
  }

  int64_t now_ = kStart;
  LcmBus bus_{"memq://"};
  std::vector<tendon_state_t> states_;
  std::vector<std::string> rejections_;
  PlantPoll last_poll_;
};

TEST_F(PlantLinkTest, PublishesTheStateAtItsRateAndTakesCommands) {
  PlantWorld world(Example().model, Options(50.0));
  PlantLink link(bus_, world);
  Run(link, 1.0);
  ASSERT_EQ(states_.size(), 50u) << "50 Hz over 1 s of 1 ms polls";
  for (size_t i = 0; i < states_.size(); ++i) {
    EXPECT_EQ(states_[i].header.seq, static_cast<int64_t>(i));
    EXPECT_EQ(states_[i].header.utime, kStart + static_cast<int64_t>(i) * 20 * kMs);
  }
  EXPECT_EQ(link.states_published(), 50);

  const Eigen::Vector4d y(1.0, 2.5, 0.5, 1.5);
  bus_.Publish(channels::kPlantCommand, Command(y));
  bus_.Publish(channels::kPlantCommand, Command(Eigen::Vector3d(1, 1, 1)));
  Run(link, 0.1);
  EXPECT_EQ(world.Snapshot().positions, Eigen::VectorXd(y));
  ASSERT_EQ(rejections_.size(), 1u);
  EXPECT_THAT(rejections_[0], HasSubstr("SHAPESENSE_PLANT_COMMAND: displacement_mm: expected 4"));
  EXPECT_EQ(states_.back().displacement_mm, std::vector<double>(y.data(), y.data() + 4));

  // Cut: nothing goes out, commands are lost (and counted).
  link.set_connected(false);
  const size_t published = states_.size();
  bus_.Publish(channels::kPlantCommand, Command(Eigen::Vector4d::Constant(2.0)));
  HandleAll();
  const PlantPoll cut = link.Poll(now_);
  EXPECT_EQ(cut.dropped, 1);
  Run(link, 0.5);
  EXPECT_EQ(states_.size(), published);
  EXPECT_EQ(world.Snapshot().positions, Eigen::VectorXd(y));
}

TEST_F(PlantLinkTest, TheControllersRigDriverSpeaksTheProtocol) {
  PlantWorld world(Example().model, Options(100.0));
  PlantLink link(bus_, world);
  RigActuatorOptions rig;
  rig.state_timeout_s = 0.2;
  rig.connect_timeout_s = 1.0;
  RigPlantDriver driver(bus_, 4, rig, [this] { return now_; });
  link.Poll(now_);  // the plant's first state, which Connect waits for
  driver.Connect();
  ASSERT_TRUE(driver.Status().ok()) << driver.Status().reason;
  EXPECT_EQ(driver.ReadPositions().mm, std::vector<double>(4, 0.0));

  const std::vector<double> targets = {1.0, 1.5, 2.0, 0.25};
  driver.CommandTargets(targets);
  Run(link, 0.05);
  EXPECT_EQ(world.Snapshot().positions, Eigen::Map<const Eigen::VectorXd>(targets.data(), 4));
  EXPECT_EQ(driver.ReadPositions().mm, targets);
  EXPECT_TRUE(driver.Status().ok());

  driver.Stop();
  Run(link, 0.05);
  EXPECT_EQ(world.Snapshot().stops, 1);
  EXPECT_EQ(driver.ReadPositions().mm, targets) << "a stop holds where they stand";
  EXPECT_TRUE(rejections_.empty()) << rejections_.front();

  // The plant falls silent: within state_timeout_s the link is lost.
  for (int i = 0; i < 15; ++i) now_ += 10 * kMs;
  EXPECT_TRUE(driver.Status().ok()) << "0.15 s silent is within state_timeout_s";
  now_ += 100 * kMs;
  const ActuatorStatus status = driver.Status();
  EXPECT_EQ(status.state, ActuatorState::kDisconnected);
  EXPECT_THAT(status.reason, HasSubstr("rig: link lost: no plant state on SHAPESENSE_PLANT_STATE"));
}

}  // namespace
}  // namespace shapesense
