#include "tests/services/controller/fake_rig_plant.h"

#include <cmath>

#include "runtime/lcm/channels.h"
#include "shapesense/tendon_state_t.hpp"

namespace shapesense::testing {

FakeRigPlant::FakeRigPlant(LcmBus& bus, const ManipulatorOptions& nominal,
                           const FakeRigOptions& options, MicrosecondClock clock,
                           const Eigen::VectorXd& initial)
    : bus_(bus),
      plant_(nominal, options.plant, initial),
      options_(options),
      clock_(std::move(clock)),
      rng_(options.seed) {
  bus_.Subscribe<tendon_command_t>(
      channels::kPlantCommand,
      [this](tendon_command_t&& command, const std::string&, int64_t) { OnCommand(command); });
}

void FakeRigPlant::OnCommand(const tendon_command_t& command) {
  if (!answering_) return;
  if (command.mode == tendon_command_t::MODE_STOP) {
    ++stops_;
    return;
  }
  const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(
      command.displacement_mm.data(), static_cast<Eigen::Index>(command.displacement_mm.size()));
  if (y.size() != plant_.commanded().size() || !y.allFinite()) return;
  plant_.Command(y);
  ++moves_;
}

void FakeRigPlant::PublishState(int64_t now) {
  tendon_state_t state{};
  state.header.seq = seq_++;
  state.header.utime = now;
  const Eigen::VectorXd& y = plant_.commanded();
  state.num_tendons = static_cast<int32_t>(y.size());
  for (Eigen::Index i = 0; i < y.size(); ++i) {
    const double tension = plant_.state().tensions(i);
    state.displacement_mm.push_back(y(i));
    state.tension_n.push_back(tension);
    state.fault.push_back(tension <= 0.0 ? tendon_state_t::FAULT_SLACK : 0);
  }
  bus_.Publish(channels::kPlantState, state);
}

void FakeRigPlant::Sample(int64_t now) {
  std::normal_distribution<double> kappa(0.0, options_.curvature_noise);
  std::normal_distribution<double> strain(0.0, options_.strain_noise);
  const Configuration q =
      plant_.configuration() + Configuration(kappa(rng_), kappa(rng_), strain(rng_), strain(rng_));
  shape_t shape{};
  shape.trigger_seq = trigger_seq_++;
  shape.trigger_utime = now;
  shape.valid = true;
  shape.has_configuration = true;
  for (int i = 0; i < 4; ++i) shape.q[i] = q(i);
  const Vec3 tip = TrueTip();
  for (int i = 0; i < 3; ++i) shape.tip[i] = tip(i);
  in_flight_.push_back(shape);
  last_trigger_utime_ = now;
}

void FakeRigPlant::Tick() {
  const int64_t now = clock_();
  if (answering_) PublishState(now);
  const int64_t period = static_cast<int64_t>(std::llround(options_.sensing_period * 1e6));
  if (next_sample_utime_ == 0) next_sample_utime_ = now;
  if (sensing_ && now >= next_sample_utime_) {
    Sample(now);
    next_sample_utime_ = std::max(next_sample_utime_ + period, now);
  }
  const int64_t latency = static_cast<int64_t>(std::llround(options_.latency * 1e6));
  while (!in_flight_.empty() && in_flight_.front().trigger_utime + latency <= now) {
    shape_t& shape = in_flight_.front();
    shape.header.seq = shape.trigger_seq;
    shape.header.utime = now;
    shape.header.data_age_us = now - shape.trigger_utime;
    bus_.Publish(channels::kShape, shape);
    in_flight_.pop_front();
  }
}

}  // namespace shapesense::testing
