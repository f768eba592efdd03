#include "services/rig_sim/plant_world.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "libs/core/error.h"
#include "libs/mechanics/configuration_geometry.h"
#include "libs/mechanics/configuration_sensing.h"
#include "runtime/config_file.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/shape_message.h"
#include "runtime/lcm/truth_message.h"

namespace shapesense {
namespace {

constexpr int64_t kNever = std::numeric_limits<int64_t>::min();
// Configurations kept for scenes of times already passed: seconds of them at
// a poll every few ms while the actuators move, far more while they rest.
constexpr size_t kHistorySize = 2048;

Eigen::VectorXd Initial(const ManipulatorOptions& model, const PlantWorldOptions& options) {
  if (options.initial_displacements.empty()) {
    return Eigen::VectorXd::Zero(static_cast<Eigen::Index>(model.tendons.size()));
  }
  return Eigen::Map<const Eigen::VectorXd>(
      options.initial_displacements.data(),
      static_cast<Eigen::Index>(options.initial_displacements.size()));
}

// A configuration the actuators may reach: finite, within max_strain and
// max_bend_angle (and so one the renderer can draw).
bool WithinLimits(const Configuration& q, const SectionLengths& rest,
                  const PlantWorldOptions& options) {
  const double bend = std::hypot(q(kKappaX), q(kKappaZ)) * CompressedLengths(q, rest).distal;
  return q.allFinite() && std::abs(q(kStrainProximal)) <= options.max_strain &&
         std::abs(q(kStrainDistal)) <= options.max_strain && bend <= options.max_bend_angle;
}

// "" or why the options and the model do not fit each other.
std::string Misfit(const ManipulatorOptions& model, const PlantWorldOptions& options) {
  if (std::string error = options.Validate(); !error.empty()) return error;
  const size_t tendons = model.tendons.size();
  if (!options.initial_displacements.empty() && options.initial_displacements.size() != tendons) {
    return "initial_displacements: expected " + std::to_string(tendons) +
           " (the model's tendons) or none, got " +
           std::to_string(options.initial_displacements.size());
  }
  const SectionLengths rest{model.proximal_length, model.distal_length};
  const ManipulatorGeometry geometry{rest, options.base.WorldFromBase(), options.scene.tapes};
  if (const std::string error = geometry.Validate(); !error.empty()) return "scene." + error;
  const TendonPlant start(model, options.plant, Initial(model, options));
  if (!WithinLimits(start.configuration(), rest, options)) {
    return "initial_displacements: the start is beyond max_strain or max_bend_angle";
  }
  return "";
}

const PlantWorldOptions& Checked(const ManipulatorOptions& model,
                                 const PlantWorldOptions& options) {
  if (const std::string error = Misfit(model, options); !error.empty()) {
    throw std::invalid_argument("plant world: " + error);
  }
  return options;
}

// "" when the plant may carry out `command`, else the reason.
std::string CommandError(const tendon_command_t& command, int tendons) {
  const int8_t mode = command.mode;
  if (mode < tendon_command_t::MODE_HOLD || mode > tendon_command_t::MODE_STOP) {
    return "mode: expected MODE_HOLD .. MODE_STOP (0-4), got " + std::to_string(mode);
  }
  // A stop carries the positions the driver last saw, which the plant does
  // not need: nothing in it can make the plant refuse to stop.
  if (mode == tendon_command_t::MODE_STOP || mode == tendon_command_t::MODE_HOLD) return "";
  const size_t count = command.displacement_mm.size();
  if (command.num_tendons < 0 || static_cast<size_t>(command.num_tendons) != count) {
    return "num_tendons: " + std::to_string(command.num_tendons) + " but " + std::to_string(count) +
           " displacements";
  }
  if (count != static_cast<size_t>(tendons)) {
    return "displacement_mm: expected " + std::to_string(tendons) +
           " displacements (the plant's tendons), got " + std::to_string(count);
  }
  for (size_t i = 0; i < count; ++i) {
    if (!std::isfinite(command.displacement_mm[i])) {
      return "displacement_mm[" + std::to_string(i) + "]: expected a finite number, got " +
             Number(command.displacement_mm[i]);
    }
  }
  return "";
}

double Seconds(int64_t microseconds) { return static_cast<double>(microseconds) * 1e-6; }

}  // namespace

std::string PlantWorldOptions::Validate() const {
  if (manipulator.empty()) return "manipulator: expected the model file, got nothing";
  if (const std::string error = plant.Validate(); !error.empty()) return "plant." + error;
  if (const std::string error = scene.Validate(); !error.empty()) return "scene." + error;
  for (size_t i = 0; i < initial_displacements.size(); ++i) {
    if (!std::isfinite(initial_displacements[i])) {
      return "initial_displacements[" + std::to_string(i) + "]: expected a finite number, got " +
             Number(initial_displacements[i]);
    }
  }
  for (const std::string& error :
       {base.Validate(), ExpectWithin("actuator_speed", actuator_speed, {0.0, 1e6}),
        ExpectWithin("max_strain", max_strain, {0.0, 0.9, true}),
        ExpectWithin("max_bend_angle", max_bend_angle, {0.0, 4.0 * std::numbers::pi, true}),
        ExpectWithin("state_rate_hz", state_rate_hz, {1.0, 1000.0}),
        ExpectWithin("command_timeout_s", command_timeout_s, {0.0, 1e6})}) {
    if (!error.empty()) return error;
  }
  return "";
}

PlantWorldSetup LoadPlantWorldSetup(const std::filesystem::path& config_file) {
  PlantWorldSetup setup{LoadOptionsFile<PlantWorldOptions>(config_file), {}};
  setup.options.manipulator = ResolveConfigPath(config_file, setup.options.manipulator).string();
  setup.model =
      ParseManipulatorYaml(ReadTextFile(setup.options.manipulator), setup.options.manipulator);
  if (const std::string error = Misfit(setup.model, setup.options); !error.empty()) {
    throw InputError(config_file.string() + ": " + error);
  }
  return setup;
}

// ---- PlantWorld --------------------------------------------------------------

PlantWorld::PlantWorld(const ManipulatorOptions& nominal, const PlantWorldOptions& options)
    : options_(Checked(nominal, options)),
      num_tendons_(static_cast<int>(nominal.tendons.size())),
      rest_{nominal.proximal_length, nominal.distal_length},
      world_from_base_(options.base.WorldFromBase()),
      plant_(nominal, options.plant, Initial(nominal, options)),
      target_(plant_.commanded()),
      now_(kNever),
      last_command_utime_(kNever) {
  history_.push_back({kNever, plant_.configuration()});
}

std::string PlantWorld::OnCommand(const tendon_command_t& command, int64_t utime) {
  std::string why = CommandError(command, num_tendons_);
  std::lock_guard lock(mutex_);
  if (!why.empty()) {
    ++counters_.rejected;
    counters_.last_rejection = why;
    return why;
  }
  AdvanceLocked(utime);  // the move so far went toward the previous target
  if (command.mode == tendon_command_t::MODE_STOP || command.mode == tendon_command_t::MODE_HOLD) {
    target_ = plant_.commanded();
    stalled_ = false;
    ++counters_.stops;
  } else {
    target_ = Eigen::Map<const Eigen::VectorXd>(command.displacement_mm.data(), num_tendons_);
  }
  last_command_utime_ = std::max(last_command_utime_, utime);
  ++counters_.commands;
  return "";
}

void PlantWorld::Advance(int64_t utime) {
  std::lock_guard lock(mutex_);
  AdvanceLocked(utime);
}

void PlantWorld::AdvanceLocked(int64_t utime) {
  if (now_ == kNever) now_ = utime;
  utime = std::max(utime, now_);  // time never goes back; an instant move still happens
  const int64_t deadline =
      options_.command_timeout_s > 0.0 && last_command_utime_ != kNever
          ? last_command_utime_ + std::llround(options_.command_timeout_s * 1e6)
          : std::numeric_limits<int64_t>::max();
  const int64_t moving_until = std::min(utime, std::max(deadline, now_));
  Move(Seconds(moving_until - now_), moving_until);
  if (utime > deadline && target_ != plant_.commanded()) {
    target_ = plant_.commanded();  // the drive's watchdog
    stalled_ = false;
    ++counters_.timeouts;
  }
  now_ = utime;
}

void PlantWorld::Move(double seconds, int64_t end_utime) {
  const Eigen::VectorXd& from = plant_.commanded();
  Eigen::VectorXd to = target_;
  if (options_.actuator_speed > 0.0) {
    const double step = options_.actuator_speed * seconds;
    for (Eigen::Index i = 0; i < to.size(); ++i) {
      const double gap = target_(i) - from(i);
      if (std::abs(gap) > step) to(i) = from(i) + std::copysign(step, gap);  // else arrives
    }
  }
  if (to == from) return;
  TendonPlant moved = plant_;
  moved.Command(to);
  stalled_ = !WithinLimits(moved.configuration(), rest_, options_);
  if (stalled_) return;
  plant_ = std::move(moved);
  history_.push_back({end_utime, plant_.configuration()});
  if (history_.size() > kHistorySize) history_.pop_front();
}

Configuration PlantWorld::ConfigurationAtUtime(int64_t utime) {
  std::lock_guard lock(mutex_);
  if (now_ == kNever || utime >= now_) {
    AdvanceLocked(utime);
    return plant_.configuration();
  }
  const auto sample = std::find_if(history_.rbegin(), history_.rend(),
                                   [&](const auto& kept) { return kept.utime <= utime; });
  // Older than the history: the oldest kept.
  return sample != history_.rend() ? sample->q : history_.front().q;
}

TubeScene PlantWorld::SceneAtUtime(int64_t utime) {
  const Configuration q = ConfigurationAtUtime(utime);
  return SceneOfConfiguration(q, rest_, world_from_base_, options_.scene);
}

tendon_state_t PlantWorld::State(int64_t utime) {
  std::lock_guard lock(mutex_);
  AdvanceLocked(utime);
  tendon_state_t state{};
  state.header.utime = now_;
  state.num_tendons = num_tendons_;
  const Eigen::VectorXd& positions = plant_.commanded();
  const Eigen::VectorXd& tensions = plant_.state().tensions;
  for (int i = 0; i < num_tendons_; ++i) {
    int32_t fault = tensions(i) <= 0.0 ? tendon_state_t::FAULT_SLACK : 0;
    if (stalled_ && target_(i) != positions(i)) fault |= tendon_state_t::FAULT_LIMIT;
    state.displacement_mm.push_back(positions(i));
    state.tension_n.push_back(tensions(i));
    state.fault.push_back(fault);
  }
  return state;
}

shape_t PlantWorld::TruthMessage(const TubeScene& scene, int64_t trigger_seq, int64_t trigger_utime,
                                 int64_t header_seq, int64_t publish_utime) const {
  if (!scene.configuration) {
    throw std::invalid_argument("PlantWorld::TruthMessage: the scene carries no configuration");
  }
  const Configuration& q = *scene.configuration;
  TrajectoryPose straight;  // FrameSetTruth's curvature, replaced below
  straight.length = 1.0;
  shape_t truth =
      FrameSetTruth(scene, straight, trigger_seq, trigger_utime, header_seq, publish_utime);
  // The scene starts body_start along the straight proximal section (or at
  // the junction, for a body_start beyond it): curved from the junction on.
  const double proximal = CompressedLengths(q, rest_).proximal;
  const double junction = proximal - std::min(options_.scene.body_start, proximal);
  const double kappa = std::hypot(q(kKappaX), q(kKappaZ));
  for (size_t i = 0; i < truth.curvature.size(); ++i) {
    truth.curvature[i] = truth.arc_length[i] >= junction - 1e-6 ? kappa : 0.0;
  }
  SetMessageConfiguration(q, 0.0, &truth);
  return truth;
}

PlantSnapshot PlantWorld::Snapshot() const {
  std::lock_guard lock(mutex_);
  PlantSnapshot snapshot = counters_;
  snapshot.utime = now_;
  snapshot.target = target_;
  snapshot.positions = plant_.commanded();
  snapshot.tendon_displacements = plant_.tendon_displacements();
  snapshot.tensions = plant_.state().tensions;
  snapshot.configuration = plant_.configuration();
  snapshot.stalled = stalled_;
  return snapshot;
}

// ---- PlantLink ---------------------------------------------------------------

PlantLink::PlantLink(LcmBus& bus, PlantWorld& world)
    : bus_(bus),
      world_(world),
      inbox_(std::make_shared<Inbox>()),
      period_us_(std::max<int64_t>(1, std::llround(1e6 / world.options().state_rate_hz))) {
  // The callback only queues, and holds the inbox, never the link.
  bus_.Subscribe<tendon_command_t>(
      channels::kPlantCommand,
      [inbox = inbox_](tendon_command_t&& command, const std::string&, int64_t) {
        std::lock_guard lock(inbox->mutex);
        if (inbox->commands.size() >= kInboxCapacity) {
          inbox->commands.pop_front();
          ++inbox->dropped;
        }
        inbox->commands.push_back(std::move(command));
      });
}

void PlantLink::HandCommands(PlantPoll* poll, int64_t now_utime) {
  std::deque<tendon_command_t> commands;
  {
    std::lock_guard lock(inbox_->mutex);
    commands.swap(inbox_->commands);
    poll->dropped = std::exchange(inbox_->dropped, 0);
  }
  if (!connected_) {
    poll->dropped += static_cast<int64_t>(commands.size());
    return;
  }
  for (const tendon_command_t& command : commands) {
    const std::string why = world_.OnCommand(command, now_utime);
    if (why.empty()) {
      ++poll->accepted;
    } else {
      poll->rejections.push_back(std::string(channels::kPlantCommand) + ": " + why);
    }
  }
}

PlantPoll PlantLink::Poll(int64_t now_utime) {
  PlantPoll poll;
  HandCommands(&poll, now_utime);
  world_.Advance(now_utime);
  if (!connected_ || now_utime < next_state_utime_) return poll;
  tendon_state_t state = world_.State(now_utime);
  state.header.seq = seq_++;
  poll.published = bus_.Publish(channels::kPlantState, state);
  if (poll.published) ++published_;
  // On the rate's grid from the first state; a late poll does not bunch the next.
  next_state_utime_ =
      next_state_utime_ == 0 ? now_utime + period_us_ : next_state_utime_ + period_us_;
  if (next_state_utime_ <= now_utime) next_state_utime_ = now_utime + period_us_;
  return poll;
}

}  // namespace shapesense
