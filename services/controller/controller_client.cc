#include "services/controller/controller_client.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <thread>

#include "libs/mechanics/configuration_geometry.h"
#include "runtime/devices/device_clock.h"
#include "runtime/lcm/channels.h"
#include "shapesense/tendon_command_t.hpp"
#include "shapesense/tendon_state_t.hpp"

namespace shapesense {
namespace {

constexpr size_t kShapeQueue = 16;
constexpr size_t kTargetQueue = 16;
constexpr size_t kEstopQueue = 16;
constexpr const char* kName = "shapesense-controller";

// The gate's reasons for holding or stopping (not those that only shape a move).
constexpr uint32_t kHoldReasons = kGateInvalidProposal | kGateEmergencyStop | kGateSensingLost |
                                  kGateAwaitingSensing | kGateSensingStale | kGateInvalidPeriod |
                                  kGateStoppedUntilRearmed;

// Keeps the newest `capacity`; true when the oldest had to go.
template <class T>
bool PushBounded(std::deque<T>& queue, T item, size_t capacity) {
  const bool full = queue.size() >= capacity;
  if (full) queue.pop_front();
  queue.push_back(std::move(item));
  return full;
}

int8_t ModeOf(ControlMode mode) {
  switch (mode) {
    case ControlMode::kOpenLoop:
      return tendon_command_t::MODE_OPEN_LOOP;
    case ControlMode::kModelLess:
      return tendon_command_t::MODE_MODEL_LESS;
    default:
      return tendon_command_t::MODE_CLOSED_LOOP;
  }
}

std::string Fixed(double value, int decimals) {
  char text[48];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

Eigen::VectorXd ToVector(const std::vector<double>& values) {
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

}  // namespace

ControllerClient::ControllerClient(const ControllerSetup& setup, LcmBus& bus,
                                   ActuatorDriver& driver, ControllerLog& log,
                                   MicrosecondClock clock, std::ostream* progress)
    : setup_(setup),
      bus_(bus),
      driver_(driver),
      log_(log),
      clock_(clock ? std::move(clock) : MicrosecondClock(EpochMicros)),
      progress_(progress),
      model_(setup.manipulator),
      resolver_(model_, setup.controller),
      controller_(MakeController(model_, setup.controller)),
      measured_(Eigen::VectorXd::Zero(model_.num_tendons())) {
  if (setup_.client.stream_targets()) tip_worker_ = std::make_unique<TipTargetWorker>(resolver_);
  Subscribe();
}

void ControllerClient::Subscribe() {
  // Callbacks only queue; the step does the work.
  bus_.Subscribe<shape_t>(channels::kShape, [this](shape_t&& shape, const std::string&, int64_t) {
    status_.Received();
    const int64_t measured = clock_() - shape.header.data_age_us;
    if (PushBounded(pending_shapes_, ArrivedShape{std::move(shape), measured}, kShapeQueue)) {
      InputDropped();
    }
  });
  bus_.Subscribe<estop_t>(channels::kEstop, [this](estop_t&& estop, const std::string&, int64_t) {
    status_.Received();
    if (PushBounded(pending_estops_, std::move(estop), kEstopQueue)) InputDropped();
  });
  if (!setup_.client.stream_targets()) return;
  bus_.Subscribe<configuration_target_t>(
      channels::kTarget, [this](configuration_target_t&& target, const std::string&, int64_t) {
        status_.Received();
        // A start time is the sender's clock: moved onto this one by the
        // sender's measured offset (its own messages are a sample of it).
        if (target.start_utime != 0) {
          target.start_utime -= bus_.clock_offsets().OffsetOf(target.header.host).value_or(0);
        }
        if (PushBounded(pending_targets_, std::move(target), kTargetQueue)) InputDropped();
      });
}

void ControllerClient::Start() {
  driver_.Connect();
  const ActuatorPositions positions = driver_.ReadPositions();
  if (static_cast<int>(positions.mm.size()) != model_.num_tendons()) {
    throw ActuatorError(driver_.description() + ": reports " + std::to_string(positions.mm.size()) +
                        " positions, the model has " + std::to_string(model_.num_tendons()) +
                        " tendons");
  }
  measured_ = ToVector(positions.mm);
  if (!measured_.allFinite()) throw ActuatorError(driver_.description() + ": a position is NaN");
  gate_.emplace(model_, setup_.controller.limits, setup_.controller.watchdog, measured_);
  start_utime_ = clock_();
  next_flush_utime_ = start_utime_;
  const std::string targets =
      setup_.client.stream_targets()
          ? "targets streamed on " + std::string(channels::kTarget)
          : "a trajectory of " + std::to_string(setup_.trajectory.targets.size()) + " targets";
  if (progress_ != nullptr) {
    *progress_ << kName << ": running: " << setup_.controller.mode << " at "
               << setup_.controller.loop_rate << " Hz, actuators " << driver_.description() << ", "
               << targets << std::endl;
  }
}

int ControllerClient::HandleBus(int timeout_ms) {
  const int handled = bus_.Handle(timeout_ms);
  AfterMessage();
  return handled;
}

void ControllerClient::DrainBus() {
  // Bounded: what is waiting now, plus what the handlers publish meanwhile.
  for (int i = 0; i < 10000 && HandleBus(0) > 0; ++i) {
  }
}

// More came between two steps than the queues keep (or the tip solver's).
void ControllerClient::InputDropped() {
  ++counters_.inputs_dropped;
  status_.Dropped();
}

void ControllerClient::AfterMessage() {
  if (bus_.Rejected() != counters_.messages_rejected) {
    counters_.messages_rejected = bus_.Rejected();
    counters_.last_message_rejection = bus_.LastRejection();
    Event("message rejected: " + bus_.LastRejection());
  }
  ReactToEmergencyStops();
}

void ControllerClient::ReactToEmergencyStops() {
  while (!pending_estops_.empty()) {
    const estop_t estop = std::move(pending_estops_.front());
    pending_estops_.pop_front();
    const std::string who = (estop.source.empty() ? "?" : estop.source) +
                            (estop.reason.empty() ? "" : ": " + estop.reason);
    if (estop.engaged) {
      release_requested_ = false;
      if (estop_engaged_) continue;
      estop_engaged_ = true;
      ++counters_.estops;
      driver_.Stop();  // now, not at the next step
      Event("e-stop engaged by " + who);
    } else if (estop_engaged_ || was_stopped_) {
      release_requested_ = true;
      Event("release from " + who);
    }
  }
}

double ControllerClient::SecondsSinceStart(int64_t utime) const {
  return static_cast<double>(utime - start_utime_) * 1e-6;
}

void ControllerClient::TakeShapes(int64_t now) {
  for (; !pending_shapes_.empty(); pending_shapes_.pop_front()) {
    const shape_t& shape = pending_shapes_.front().shape;
    std::string why;
    const ShapeUse use = CheckShape(shape, &why);
    if (use == ShapeUse::kMalformed) {
      ++counters_.shapes_rejected;
      counters_.last_shape_rejection = why;
      status_.Rejected();
      Event("shape rejected: " + why);
      continue;
    }
    log_.WriteEvent(channels::kShape, LoggedShape(shape), now);
    if (use == ShapeUse::kNoConfiguration) {
      ++counters_.shapes_without_configuration;
      continue;
    }
    if (shape.trigger_utime <= sensed_trigger_utime_) continue;  // late: a newer one is in use
    ++counters_.shapes_used;
    sensed_trigger_utime_ = shape.trigger_utime;
    sensed_seq_ = shape.trigger_seq;
    sensed_.configuration = Configuration(shape.q[0], shape.q[1], shape.q[2], shape.q[3]);
    sensed_.time = SecondsSinceStart(pending_shapes_.front().measured_utime);
    sensed_.valid = true;
  }
}

void ControllerClient::TakeTargets(double time, int64_t now) {
  for (; !pending_targets_.empty(); pending_targets_.pop_front()) {
    const int64_t receipt = next_receipt_++;
    const configuration_target_t& message = pending_targets_.front();
    Target target;
    std::string why;
    if (!TargetFromMessage(message, now, &target, &why)) {
      RejectTarget(why);
    } else if (target.kind == TargetKind::kTipPosition) {
      with_tip_solver_[receipt] = message;
      if (!tip_worker_->Submit({receipt, target})) InputDropped();
    } else {
      ApplyTarget(receipt, resolver_.Resolve(target), message, time, now);
    }
  }
  for (const TipTargetWorker::Result& result : tip_worker_->TakeResults()) {
    const configuration_target_t message = with_tip_solver_[result.receipt];
    // Dropped from the worker's queue: never to come back.
    with_tip_solver_.erase(with_tip_solver_.begin(), with_tip_solver_.upper_bound(result.receipt));
    ApplyTarget(result.receipt, result.resolved, message, time, now);
  }
}

void ControllerClient::RejectTarget(const std::string& why) {
  ++counters_.targets_rejected;
  counters_.last_target_rejection = why;
  status_.Rejected();
  status_.Note("target rejected: " + why);
  Event("target rejected: " + why);
}

void ControllerClient::ApplyTarget(int64_t receipt, const ResolvedTarget& resolved,
                                   const configuration_target_t& message, double time,
                                   int64_t now) {
  if (!resolved.ok) {
    RejectTarget(resolved.reason);
    return;
  }
  if (receipt < applied_receipt_) {
    Event("target superseded: a newer one came first out of the tip solver");
    return;
  }
  applied_receipt_ = receipt;
  // The move starts from where the target is now, so a new target mid-move
  // does not jump.
  const Configuration from = has_streamed_target() ? ramp_.At(time) : resolved.configuration;
  const int64_t start = message.start_utime != 0 ? message.start_utime : now;
  ramp_ = {from, resolved.configuration, SecondsSinceStart(start), message.duration_s};
  ++counters_.targets_accepted;
  Event("target accepted" + (message.source.empty() ? "" : " from " + message.source));
}

bool ControllerClient::TargetNow(double time, Configuration* target) const {
  if (setup_.client.stream_targets()) {
    if (has_streamed_target()) *target = ramp_.At(time);
    return has_streamed_target();
  }
  *target = TargetAt(setup_.trajectory, time);
  return true;
}

bool ControllerClient::ReadActuators() {
  try {
    const ActuatorStatus status = driver_.Status();
    if (!status.ok()) {
      throw ActuatorError(status.reason.empty() ? ActuatorStateName(status.state) : status.reason);
    }
    const ActuatorPositions positions = driver_.ReadPositions();
    if (static_cast<int>(positions.mm.size()) != model_.num_tendons()) {
      throw ActuatorError("read " + std::to_string(positions.mm.size()) + " positions for " +
                          std::to_string(model_.num_tendons()) + " tendons");
    }
    measured_ = ToVector(positions.mm);
    return true;
  } catch (const ActuatorError& e) {
    Fail(e.what());
    return false;
  }
}

void ControllerClient::Fail(const std::string& why) {
  error_ = "actuators (" + driver_.description() + ") failed: " + why;
  driver_.Stop();  // whatever can still be reached holds
  status_.Error(error_);
  Event(error_);
}

const StepRecord& ControllerClient::Step() {
  const int64_t now = clock_();
  record_ = StepRecord{};
  record_.utime = now;
  record_.time = SecondsSinceStart(now);
  const double dt = record_.time - last_time_;
  last_time_ = record_.time;
  TakeShapes(now);
  if (tip_worker_) TakeTargets(record_.time, now);
  if (!driver_failed() && ReadActuators()) {
    Control(dt);
  } else {
    record_.command = gate_->command();
    record_.proposal = record_.command;
    record_.tensions = gate_->envelope().Tensions(record_.command);
    record_.mode = tendon_command_t::MODE_STOP;
  }
  record_.measured = measured_;
  Report();
  return record_;
}

void ControllerClient::Control(double dt) {
  ControlInput input;
  input.time = record_.time;
  input.dt = dt;
  input.sensed = sensed_;
  input.last_command = gate_->command();
  record_.has_target = TargetNow(record_.time, &input.target);
  record_.target = input.target;
  record_.sensed = sensed_;
  record_.sensed_trigger_seq = sensed_.valid ? sensed_seq_ : -1;
  record_.sensing_age = input.sensing_age();
  // Without a target (a stream that has sent none yet) the command stays.
  record_.proposal = record_.has_target ? controller_->Propose(input) : gate_->command();
  const GateResult gated =
      gate_->Apply(record_.proposal, dt, record_.sensing_age, estop_engaged_ || stopping_);
  record_.command = gated.command;
  record_.reasons = gated.reasons;
  record_.tensions = gate_->envelope().Tensions(gated.command);
  record_.mode = gate_->stopped() ? tendon_command_t::MODE_STOP
                 : gated.held     ? tendon_command_t::MODE_HOLD
                                  : ModeOf(controller_->mode());
  AfterGate(gated);
  Actuate(gated.held);
}

void ControllerClient::AfterGate(const GateResult& gated) {
  if (gated.held) ++counters_.held_steps;
  if (gate_->stopped() && !was_stopped_) driver_.Stop();
  was_stopped_ = gate_->stopped();
  ShowState(gated);
  // A release clears the e-stop now; the gate re-arms at the next step, once
  // it has seen the e-stop released (SafetyGate::Rearm).
  if (rearm_pending_) {
    rearm_pending_ = false;
    const std::string refused = gate_->stopped() ? gate_->Rearm() : "";
    Event(refused.empty() ? "re-armed" : "release refused: " + refused);
  }
  if (release_requested_) {
    release_requested_ = false;
    estop_engaged_ = false;
    rearm_pending_ = true;
  }
}

void ControllerClient::Actuate(bool held) {
  if (held) return;  // the actuators keep the previous command
  try {
    driver_.CommandTargets(std::span<const double>(record_.command.data(),
                                                   static_cast<size_t>(record_.command.size())));
    record_.sent = true;
    ++counters_.commands_sent;
  } catch (const ActuatorError& e) {
    Fail(e.what());
    record_.mode = tendon_command_t::MODE_STOP;
  }
}

void ControllerClient::ShowState(const GateResult& gated) {
  const std::string reasons = DescribeGateReasons(gated.reasons & kHoldReasons);
  const std::string state = gate_->stopped() ? "stopped (" + reasons + ")"
                            : gated.held     ? "holding (" + reasons + ")"
                                             : "moving";
  if (state == shown_state_) return;
  shown_state_ = state;
  // A clean stop goes through the gate as an e-stop; it ends the run anyway.
  if (stopping_) return;
  Event(gate_->stopped() ? state + "; latched until a release on " + channels::kEstop : state);
}

void ControllerClient::Event(const std::string& what) {
  pending_note_ += (pending_note_.empty() ? "" : "; ") + what;
  if (progress_ == nullptr) return;
  const double time = started() ? SecondsSinceStart(clock_()) : 0.0;
  *progress_ << kName << ": " << Fixed(time, 2) << " s: " << what << std::endl;
}

void ControllerClient::Report() {
  record_.note = std::move(pending_note_);
  pending_note_.clear();
  PublishCommand();
  PublishState();
  log_.WriteStep(record_);
  ++counters_.steps;
  status_.MaybePublish(bus_, record_.utime);
  if (record_.utime >= next_flush_utime_) {
    if (const std::string error = log_.Flush(); !error.empty()) status_.Error(error);
    next_flush_utime_ = record_.utime + SecondsToMicros(setup_.client.log.flush_period_s);
  }
  MaybeProgress();
}

void ControllerClient::PublishCommand() {
  tendon_command_t command{};
  command.header.seq = seq_;
  command.header.utime = record_.utime;
  command.num_tendons = static_cast<int32_t>(record_.command.size());
  command.displacement_mm.assign(record_.command.data(),
                                 record_.command.data() + record_.command.size());
  command.source_trigger_seq =
      controller_->mode() == ControlMode::kOpenLoop ? -1 : record_.sensed_trigger_seq;
  command.mode = record_.mode;
  command.gate_reasons = static_cast<int32_t>(record_.reasons);
  if (bus_.Publish(channels::kTendonCommand, command)) status_.Published();
  log_.WriteEvent(channels::kTendonCommand, command, record_.utime);
}

void ControllerClient::PublishState() {
  tendon_state_t state{};
  state.header.seq = seq_++;
  state.header.utime = record_.utime;
  const int n = static_cast<int>(measured_.size());
  state.num_tendons = n;
  const Eigen::VectorXd tensions = gate_->envelope().Tensions(measured_);
  const SafetyEnvelope& envelope = gate_->envelope();
  for (int i = 0; i < n; ++i) {
    int32_t fault = driver_failed() ? tendon_state_t::FAULT_LINK : 0;
    if (tensions(i) < 0.0) fault |= tendon_state_t::FAULT_SLACK;
    if (measured_(i) < envelope.low()(i) || measured_(i) > envelope.high()(i)) {
      fault |= tendon_state_t::FAULT_LIMIT;
    }
    state.displacement_mm.push_back(measured_(i));
    state.tension_n.push_back(tensions(i));
    state.fault.push_back(fault);
  }
  bus_.Publish(channels::kTendonState, state);
  log_.WriteEvent(channels::kTendonState, state, record_.utime);
}

void ControllerClient::MaybeProgress() {
  const double period = setup_.client.progress_period_s;
  if (progress_ == nullptr || period <= 0.0 || record_.time < next_progress_) return;
  next_progress_ = record_.time + period;
  std::string line = std::string(kName) + ": " + Fixed(record_.time, 2) +
                     " s: " + std::to_string(counters_.commands_sent) + " commands, " +
                     std::to_string(counters_.held_steps) + " steps held";
  if (record_.has_target && record_.sensed.valid) {
    // The tip per the model: sensed q against the target, mm.
    const SectionLengths lengths = model_.lengths();
    const double tip_error = (BaseFromTip(record_.sensed.configuration, lengths).translation() -
                              BaseFromTip(record_.target, lengths).translation())
                                 .norm();
    line += ", sensed tip " + Fixed(tip_error, 2) + " mm from the target, sensing " +
            Fixed(record_.sensing_age, 3) + " s old";
  }
  *progress_ << line << std::endl;
}

service_status_t ControllerClient::StatusSnapshot() {
  return status_.Snapshot(clock_(), bus_.Rejected());
}

void ControllerClient::Finish(const std::string& why) {
  if (finished_) return;
  if (started() && !driver_failed()) {
    stopping_ = true;
    Event("stopping: " + why);
    Step();  // the gate stops; the row says so
    driver_.Stop();
  }
  if (started()) driver_.Disconnect();  // after a failure too: close what is left of the link
  finished_ = true;
  if (const std::string error = log_.Flush(); !error.empty()) status_.Error(error);
  status_.Publish(bus_, clock_());
}

int RunControllerLoop(ControllerClient& client, const std::atomic<bool>& stop,
                      SystemdNotifier& supervisor) {
  using Clock = std::chrono::steady_clock;
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(client.loop_period()));
  const double duration_s = client.setup().client.duration_s;
  const auto start = Clock::now();
  auto next = start;
  while (!client.finished()) {
    supervisor.Watchdog();
    if (stop.load()) {
      supervisor.Stopping();
      client.Finish("SIGINT or SIGTERM");
      break;
    }
    if (duration_s > 0.0 && Clock::now() - start >= std::chrono::duration<double>(duration_s)) {
      supervisor.Stopping();
      client.Finish("the configured duration has passed");
      break;
    }
    next += period;
    if (Clock::now() > next + period) next = Clock::now();  // overrun: no burst of late steps
    while (!stop.load() && Clock::now() < next) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(next - Clock::now());
      if (left.count() < 1 ||
          client.HandleBus(static_cast<int>(std::min<int64_t>(left.count(), 20))) < 0) {
        std::this_thread::sleep_until(next);
      }
    }
    client.Step();
    if (!client.error().empty()) client.Finish("the actuators failed");
  }
  return client.error().empty() ? 0 : 1;
}

}  // namespace shapesense
