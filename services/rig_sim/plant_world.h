#pragma once

// The virtual rig's plant mode (docs/control.md, "Plant mode"): the
// manipulator the cameras see is the tendon plant (libs/sim/tendon_plant.h)
// driven by the controller over LCM, not the scripted trajectory.
//
//   SHAPESENSE_PLANT_COMMAND ──► PlantLink ──► PlantWorld::OnCommand (validated)
//                                   │ Poll ──► PlantWorld::Advance: actuators toward
//                                   │          the command ──► play ──► true model ──► q
//   SHAPESENSE_PLANT_STATE  ◄───────┘ PlantWorld::State at state_rate_hz
//   frame-set at its trigger time ──► PlantWorld::SceneAtUtime ──► renderer, truth (with q)
//
// The plant is the controller's model with its stiffnesses off and play on
// the tendons (TendonPlantOptions); the actuators move toward the latest
// command at `actuator_speed` (or at once) and stop where they stand on a
// MODE_STOP or when no command came for `command_timeout_s` (a drive's
// watchdog). A move that would take the manipulator past `max_strain` or
// `max_bend_angle` stalls the actuators (FAULT_LIMIT): the scene is always
// one the renderer can draw.

#include <Eigen/Core>
#include <array>
#include <atomic>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <mutex>
#include <numbers>
#include <string>
#include <vector>

#include "libs/geometry/types.h"
#include "libs/mechanics/base_pose.h"
#include "libs/mechanics/manipulator_options.h"
#include "libs/sim/manipulator_scene.h"
#include "libs/sim/tendon_plant.h"
#include "libs/sim/tube_scene.h"
#include "runtime/lcm/lcm_bus.h"
#include "shapesense/shape_t.hpp"
#include "shapesense/tendon_command_t.hpp"
#include "shapesense/tendon_state_t.hpp"

namespace shapesense {

// config/rig_plant.yaml documents every key.
struct PlantWorldOptions {
  // The controller's model file (config/manipulator.yaml), relative to the
  // config file's folder; the plant is drawn from it and `plant`.
  std::string manipulator = "manipulator.yaml";
  TendonPlantOptions plant;
  // world_from_base: the same keys as the shape service's `configuration:`
  // section. Keep the two equal, or the sensed q is not the plant's.
  BasePose base;
  ManipulatorSceneOptions scene;
  // Where the actuators stand at the start, mm (empty: every one at 0).
  std::vector<double> initial_displacements;
  // How fast the actuators move toward a command, mm/s (0: at once).
  double actuator_speed = 0.0;
  // The actuators stall rather than compress a section by more than this or
  // bend the distal section beyond this angle (a drive's force limit).
  double max_strain = 0.3;
  double max_bend_angle = 2.0 * std::numbers::pi;
  // SHAPESENSE_PLANT_STATE rate; keep several per the controller's
  // rig.state_timeout_s (0.5 s by default).
  double state_rate_hz = 100.0;
  // No command for this long stops the actuators where they stand (0: never).
  double command_timeout_s = 0.5;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("manipulator", manipulator,
          "the controller's model file (config/manipulator.yaml), relative to this file");
    visit("plant", plant, "how the plant differs from the model: stiffness factors, tendon play");
    base.VisitFields(visit);
    visit("scene", scene, "how the manipulator is drawn: radius, visible body, tape bands");
    visit("initial_displacements", initial_displacements,
          "actuator positions at the start, mm, one per tendon (empty: all 0)");
    visit("actuator_speed", actuator_speed,
          "how fast the actuators move toward a command, mm/s (>= 0; 0: at once)");
    visit("max_strain", max_strain,
          "the actuators stall rather than compress a section more than this (0-0.9]");
    visit("max_bend_angle", max_bend_angle,
          "the actuators stall rather than bend the distal section beyond this, rad (0-12.57]");
    visit("state_rate_hz", state_rate_hz,
          "rate of SHAPESENSE_PLANT_STATE, Hz (1-1000; several per the controller's "
          "state_timeout_s)");
    visit("command_timeout_s", command_timeout_s,
          "no command for this long stops the actuators where they stand, s (>= 0; 0: never)");
  }
  std::string Validate() const;
};

// The options and the model they name, read and checked together.
struct PlantWorldSetup {
  PlantWorldOptions options;
  ManipulatorOptions model;
};

// Reads the options (paths resolved against the file's folder) and the
// model, and checks that they fit each other (initial displacements per
// tendon, tape bands on their sections, a start within the limits). Throws
// InputError naming the file and the key.
PlantWorldSetup LoadPlantWorldSetup(const std::filesystem::path& config_file);

// The plant as it stands, for tests and logs.
struct PlantSnapshot {
  int64_t utime = 0;                     // of the last Advance
  Eigen::VectorXd target;                // where the actuators are going, mm
  Eigen::VectorXd positions;             // where they stand, mm
  Eigen::VectorXd tendon_displacements;  // at the tendons' far ends, after the play, mm
  Eigen::VectorXd tensions;              // per the true model, N
  Configuration configuration = Configuration::Zero();
  bool stalled = false;  // the last move would have passed a limit
  int64_t commands = 0;  // accepted, stops too
  int64_t rejected = 0;  // with a reason
  int64_t stops = 0;     // MODE_STOP and MODE_HOLD
  int64_t timeouts = 0;  // stops by command_timeout_s
  std::string last_rejection;
};

// The plant, its actuators and its scene. Thread-safe: the LCM side
// (PlantLink) and the cameras' threads call it at once. Time is the
// caller's (µs since the epoch); Advance ignores time going back.
class PlantWorld {
 public:
  // Throws std::invalid_argument on options that fail Validate(), initial
  // displacements of the wrong size, bands that do not fit the model or a
  // start beyond the limits.
  PlantWorld(const ManipulatorOptions& nominal, const PlantWorldOptions& options);
  explicit PlantWorld(const PlantWorldSetup& setup) : PlantWorld(setup.model, setup.options) {}

  // A command from the controller (docs/controller.md, "The virtual rig's
  // plant link"): MODE_STOP or MODE_HOLD stop the actuators where they
  // stand (always accepted: a stop is never refused); every other mode
  // aims them at displacement_mm once Advance runs. Returns "" when
  // accepted, else the reason (wrong count, a value that is not finite, an
  // unknown mode), and then changes nothing.
  std::string OnCommand(const tendon_command_t& command, int64_t utime);
  // Moves the actuators toward their target up to `utime` and lets the
  // manipulator settle (quasi-static).
  void Advance(int64_t utime);

  // The configuration at `utime`: advances to it, or for a time already
  // passed, the configuration then (from the last few seconds).
  Configuration ConfigurationAtUtime(int64_t utime);
  // The scene of ConfigurationAtUtime(utime), carrying that q.
  TubeScene SceneAtUtime(int64_t utime);
  // The actuators at `utime` (advanced to it): their positions (what a
  // drive's encoder reads, before the play), the true model's tensions,
  // FAULT_SLACK on slack tendons, FAULT_LIMIT on those a stall holds back.
  // header.seq is the publisher's to set.
  tendon_state_t State(int64_t utime);
  // The ground truth of a frame-set whose scene came from SceneAtUtime, as
  // FrameSetTruth (runtime/lcm/truth_message.h) makes it for the trajectory, with the
  // exact curvature along the centreline and q (has_configuration).
  // Throws std::invalid_argument on a scene without a configuration.
  shape_t TruthMessage(const TubeScene& scene, int64_t trigger_seq, int64_t trigger_utime,
                       int64_t header_seq, int64_t publish_utime) const;

  PlantSnapshot Snapshot() const;
  const PlantWorldOptions& options() const { return options_; }
  int num_tendons() const { return num_tendons_; }
  SectionLengths rest() const { return rest_; }
  const Pose3& world_from_base() const { return world_from_base_; }

 private:
  struct Sample {
    int64_t utime;
    Configuration q;
  };

  void AdvanceLocked(int64_t utime);
  // Moves the actuators toward the target for `seconds` (all the way when
  // the speed is 0), the move ending at `end_utime`; stalls rather than
  // pass the limits.
  void Move(double seconds, int64_t end_utime);

  const PlantWorldOptions options_;
  const int num_tendons_;
  const SectionLengths rest_;
  const Pose3 world_from_base_;
  mutable std::mutex mutex_;
  TendonPlant plant_;
  Eigen::VectorXd target_;
  int64_t now_;
  int64_t last_command_utime_;
  bool stalled_ = false;
  std::deque<Sample> history_;
  PlantSnapshot counters_;
};

// What one PlantLink::Poll did, for the caller's status.
struct PlantPoll {
  int accepted = 0;                     // commands handed to the plant
  std::vector<std::string> rejections;  // why the others were not
  int64_t dropped = 0;                  // lost to a full inbox or a cut link
  bool published = false;               // a state went out (false: none due, or LCM failed)
};

// PlantWorld on an LcmBus: subscribes to channels::kPlantCommand (the
// callback only queues) and, from Poll in its owner's loop, hands the
// commands to the world, advances it and publishes channels::kPlantState at
// the options' state_rate_hz. The bus must outlive every use of the link;
// the subscription may outlive the link.
class PlantLink {
 public:
  static constexpr size_t kInboxCapacity = 64;

  PlantLink(LcmBus& bus, PlantWorld& world);

  // Call often (every few ms): commands take effect at the next Poll, and
  // states go out at most one poll late.
  PlantPoll Poll(int64_t now_utime);
  // false: the link is cut both ways (commands dropped, no state), as a
  // plant that fell silent.
  void set_connected(bool connected) { connected_ = connected; }
  int64_t states_published() const { return published_; }

 private:
  struct Inbox {
    std::mutex mutex;
    std::deque<tendon_command_t> commands;
    int64_t dropped = 0;
  };

  void HandCommands(PlantPoll* poll, int64_t now_utime);

  LcmBus& bus_;
  PlantWorld& world_;
  std::shared_ptr<Inbox> inbox_;
  const int64_t period_us_;
  int64_t next_state_utime_ = 0;
  int64_t seq_ = 0;
  int64_t published_ = 0;
  std::atomic<bool> connected_{true};
};

}  // namespace shapesense
