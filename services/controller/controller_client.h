#pragma once

// The controller service's loop (docs/controller.md): one thread, one step
// per period at the controller's loop_rate:
//
//   latest valid sensed q (shape_t on SHAPESENSE_SHAPE) ─┐
//   target at t (trajectory) or the latest streamed one ─┼─► Controller::Propose
//                                                         └─► SafetyGate::Apply ─► driver
//
// then SHAPESENSE_TENDON_COMMAND / _STATE are published, one CSV row and
// the LCM events logged, and the 1 Hz status ("controller") published.
// Every command passes the gate; none reaches the driver while the gate
// holds or stops, nor after a driver failure. Between steps the bus is
// handled with a timeout; callbacks only queue what came. An e-stop stops
// the driver as soon as it is handled, and the gate at the next step
// (latched until a release on SHAPESENSE_ESTOP). Sensing lost stops the same
// way. A driver failure (link lost, fault) stops what can still be reached
// and ends the run with an error naming the driver.
//
// Streamed tip targets go to the tip solver on a worker thread (it can take
// several periods); configuration targets are resolved in the step.
//
// Time: the client's clock (µs since the epoch; tests give a simulated one).

#include <Eigen/Core>
#include <atomic>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <string>

#include "libs/control/controllers.h"
#include "libs/control/safety_gate.h"
#include "libs/control/targets.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/lcm/service_status.h"
#include "runtime/process/systemd_notify.h"
#include "services/controller/actuators/actuator_driver.h"
#include "services/controller/actuators/simulated_driver.h"
#include "services/controller/controller_config.h"
#include "services/controller/controller_inputs.h"
#include "services/controller/controller_log.h"
#include "services/controller/tip_target_worker.h"
#include "shapesense/configuration_target_t.hpp"
#include "shapesense/estop_t.hpp"
#include "shapesense/shape_t.hpp"

namespace shapesense {

struct ControllerCounters {
  int64_t steps = 0;
  int64_t commands_sent = 0;
  int64_t held_steps = 0;  // the gate held or stopped
  int64_t shapes_used = 0;
  int64_t shapes_without_configuration = 0;
  int64_t shapes_rejected = 0;
  int64_t targets_accepted = 0;
  int64_t targets_rejected = 0;
  int64_t messages_rejected = 0;  // malformed on the wire (the bus's count)
  int64_t inputs_dropped = 0;     // more came between two steps than the queues keep
  int64_t estops = 0;
  std::string last_target_rejection;
  std::string last_shape_rejection;
  std::string last_message_rejection;
};

class ControllerClient {
 public:
  // Subscribes to the shapes, the e-stop and (targets: stream) the targets.
  // `bus`, `driver` and `log` must outlive the client. `progress`: where
  // changes of state and progress lines go (nullptr: nowhere).
  ControllerClient(const ControllerSetup& setup, LcmBus& bus, ActuatorDriver& driver,
                   ControllerLog& log, MicrosecondClock clock = {},
                   std::ostream* progress = nullptr);

  // Connects the driver and starts the gate where the actuators stand; the
  // trajectory's time starts now. Throws ActuatorError naming the driver.
  void Start();
  // Handles what the bus brings within `timeout_ms` (one message at most),
  // reacting to an e-stop at once. Returns LcmBus::Handle's result.
  int HandleBus(int timeout_ms);
  // Handles every message already waiting.
  void DrainBus();
  // One control step at the clock's now (after Start()).
  const StepRecord& Step();
  // The clean stop (SIGINT / SIGTERM, the duration): the gate stops, a last
  // step is logged, the driver stops and disconnects, logs are flushed and
  // the last status published. Also after a failure (then only the flush).
  void Finish(const std::string& why);

  bool started() const { return gate_.has_value(); }
  bool finished() const { return finished_; }
  // Why the run failed ("" while it has not): the driver's failure.
  const std::string& error() const { return error_; }
  const ControllerCounters& counters() const { return counters_; }
  const SafetyGate& gate() const { return *gate_; }
  const StepRecord& last_step() const { return record_; }
  bool emergency_stop_engaged() const { return estop_engaged_; }
  // A streamed tip target is still with the tip solver.
  bool resolving_targets() const { return tip_worker_ != nullptr && tip_worker_->busy(); }
  double loop_period() const { return 1.0 / setup_.controller.loop_rate; }
  const ControllerSetup& setup() const { return setup_; }
  // The last status message, as published.
  service_status_t StatusSnapshot();

 private:
  void Subscribe();
  void AfterMessage();
  void InputDropped();
  bool has_streamed_target() const { return applied_receipt_ >= 0; }
  bool driver_failed() const { return !error_.empty(); }
  void ReactToEmergencyStops();
  void TakeShapes(int64_t now);
  void TakeTargets(double time, int64_t now);
  void ApplyTarget(int64_t receipt, const ResolvedTarget& resolved,
                   const configuration_target_t& message, double time, int64_t now);
  void RejectTarget(const std::string& why);
  bool TargetNow(double time, Configuration* target) const;
  bool ReadActuators();
  void Control(double dt);
  void AfterGate(const GateResult& gated);
  void Actuate(bool held);
  void Fail(const std::string& why);
  void Report();
  void PublishCommand();
  void PublishState();
  void Event(const std::string& what);
  void ShowState(const GateResult& gated);
  void MaybeProgress();
  double SecondsSinceStart(int64_t utime) const;

  ControllerSetup setup_;
  LcmBus& bus_;
  ActuatorDriver& driver_;
  ControllerLog& log_;
  MicrosecondClock clock_;
  std::ostream* progress_;
  TendonModel model_;
  TargetResolver resolver_;
  std::unique_ptr<Controller> controller_;
  std::unique_ptr<TipTargetWorker> tip_worker_;  // targets: stream only
  std::optional<SafetyGate> gate_;
  ServiceStatus status_{"controller"};
  ControllerCounters counters_;

  // A shape as it arrived, dated on this clock: its receive time less its
  // age at publish (header_t.data_age_us). Never its trigger time, which is
  // the camera host's clock, perhaps off this one.
  struct ArrivedShape {
    shape_t shape;
    int64_t measured_utime = 0;
  };

  // What the callbacks queued for the next step.
  std::deque<ArrivedShape> pending_shapes_;
  std::deque<configuration_target_t> pending_targets_;
  std::deque<estop_t> pending_estops_;

  int64_t start_utime_ = 0;
  double last_time_ = 0.0;
  SensedConfiguration sensed_;
  int64_t sensed_seq_ = -1;
  int64_t sensed_trigger_utime_ = 0;
  int64_t next_receipt_ = 0;      // order of arrival of streamed targets
  int64_t applied_receipt_ = -1;  // the newest one in use
  std::map<int64_t, configuration_target_t> with_tip_solver_;
  TargetRamp ramp_;
  Eigen::VectorXd measured_;
  StepRecord record_;
  std::string pending_note_;
  std::string shown_state_;
  double next_progress_ = 0.0;
  int64_t next_flush_utime_ = 0;
  int64_t seq_ = 0;

  bool estop_engaged_ = false;
  bool release_requested_ = false;
  bool rearm_pending_ = false;
  bool was_stopped_ = false;
  bool stopping_ = false;
  bool finished_ = false;
  std::string error_;
};

// Runs a started client at its loop rate until `stop` (SIGINT / SIGTERM),
// the configured duration, or a failure, and finishes it. Returns the exit
// code: 0 for a clean stop, 1 when the driver failed. Pings `supervisor`'s
// watchdog every step (a step that hangs stops the pings), and says
// STOPPING=1 on a stop or at the end of the duration.
int RunControllerLoop(ControllerClient& client, const std::atomic<bool>& stop,
                      SystemdNotifier& supervisor);

}  // namespace shapesense
