#pragma once

// The controller service against the fake plant peer, in one process over
// LCM memq://, on a simulated clock: each step advances the clock by the
// control period, lets the plant publish, hands every waiting message to
// its subscriber, and runs one control step. Deterministic. Over UDP
// multicast instead (a bus of one's own, e.g. with keys), each step hands
// over what it published up to a barrier: a marker the rig sends itself
// after the rest, which arrives after them (one socket keeps its order), so
// it stays deterministic whatever else the network carries.

#include <filesystem>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "services/controller/controller_client.h"
#include "services/controller/rig_plant_driver.h"
#include "tests/services/controller/fake_rig_plant.h"

namespace shapesense::testing {

// The catheter of config/manipulator.yaml.
ManipulatorOptions CatheterModel();

// Plant stiffnesses 20% off the model (the two axial ones in opposite
// senses, the worst for eps0) and tendon play 0.15 mm +-30%.
TendonPlantOptions OffNominalPlant();

// A setup for `mode` with the given targets (held until the next one's time,
// interpolation: step), the rig driver, logs in `log_dir`.
ControllerSetup TrajectorySetup(ControlMode mode, const std::vector<Target>& targets,
                                const std::filesystem::path& log_dir);
// The same with targets streamed on SHAPESENSE_TARGET.
ControllerSetup StreamSetup(ControlMode mode, const std::filesystem::path& log_dir);

// What the model reaches for q = (kappa_x, kappa_z, -, eps1) (targets.h).
Configuration ResolvedConfiguration(const ControllerSetup& setup, double kappa_x, double kappa_z,
                                    double eps1);

// A fresh folder for one test's logs.
std::filesystem::path TestLogDir();

class InProcessRig {
 public:
  // The plant's actuators start at `initial` (empty: the model's resting
  // command, straight with every tendon at the minimum tension).
  InProcessRig(const ControllerSetup& setup, const FakeRigOptions& rig,
               const Eigen::VectorXd& initial = {});
  // The same on a bus of `bus_options`.
  InProcessRig(const ControllerSetup& setup, const FakeRigOptions& rig,
               const LcmBusOptions& bus_options, const Eigen::VectorXd& initial = {});

  // The plant publishes its state; the controller connects and starts.
  void Start();
  // One control period.
  void Step();
  // `seconds` of control periods; `each` sees every step's record.
  void RunFor(double seconds, const std::function<void(const StepRecord&)>& each = {});
  // Time since Start(), s.
  double time() const { return SecondsOf(now_); }
  // A time on the clock as s since Start().
  double SecondsOf(int64_t utime) const { return static_cast<double>(utime - start_utime_) * 1e-6; }
  int64_t now() const { return now_; }

  LcmBus& bus() { return bus_; }
  FakeRigPlant& plant() { return plant_; }
  RigPlantDriver& driver() { return driver_; }
  ControllerClient& client() { return client_; }
  ControllerLog& log() { return log_; }
  const ControllerSetup& setup() const { return setup_; }
  std::string progress() const { return progress_.str(); }

 private:
  // Hands over everything published so far (UDP) or waiting (memq).
  void HandOver();

  ControllerSetup setup_;
  int64_t now_ = 1'700'000'000'000'000;  // µs since the epoch
  int64_t start_utime_ = now_;
  int64_t period_us_;
  LcmBus bus_;
  bool barriers_ = false;   // over UDP: hand over up to a barrier each step
  int64_t barrier_id_ = 0;  // this rig's markers (a log played back carries another's)
  int64_t barrier_sent_ = 0;
  int64_t barrier_seen_ = 0;
  FakeRigPlant plant_;
  RigPlantDriver driver_;
  ControllerLog log_;
  std::ostringstream progress_;
  ControllerClient client_;
};

}  // namespace shapesense::testing
