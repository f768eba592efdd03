#include "libs/control/limit_audit.h"

#include <algorithm>
#include <sstream>

namespace shapesense {
namespace {

// Rounding in the gate's arithmetic and in the sender's clock.
constexpr double kRateTolerance = 1e-9;  // relative
constexpr double kStepTolerance = 1e-9;  // mm

}  // namespace

void LimitAudit::Record(int* counter, const std::string& what) {
  ++*counter;
  if (first_.empty()) first_ = "command " + std::to_string(commands_) + ": " + what;
}

void LimitAudit::Check(const Eigen::VectorXd& command, int64_t utime, int64_t seq) {
  ++commands_;
  // The steps since the previous command seen: 1 unless some were missed.
  int64_t steps = 1;
  if (seq >= 0 && previous_seq_ >= 0 && seq > previous_seq_ + 1) {
    steps = seq - previous_seq_;
    missed_ += steps - 1;
  }
  previous_seq_ = seq;
  if (command.size() != envelope_.num_tendons() || !command.allFinite()) {
    Record(&violations_.malformed, "not one finite displacement per tendon");
    return;
  }
  if (const std::string why = envelope_.Check(command); !why.empty()) {
    Record(&violations_.range_or_tension, why);
  }
  if (previous_utime_ >= 0 && utime > previous_utime_) {
    const SafetyLimits& limits = envelope_.limits();
    const double dt = static_cast<double>(utime - previous_utime_) * 1e-6;
    const double allowed =
        limits.max_rate * std::min(dt, static_cast<double>(steps) * limits.max_step_period);
    const double step = (command - previous_).cwiseAbs().maxCoeff();
    if (step > allowed * (1.0 + kRateTolerance) + kStepTolerance) {
      std::ostringstream what;
      what << "a tendon moved " << step << " mm in " << dt << " s (at most " << allowed << ")";
      Record(&violations_.rate, what.str());
    }
  }
  previous_ = command;
  previous_utime_ = utime;
}

}  // namespace shapesense
