#pragma once

// An audit of the commands that left the safety gate, independent of it:
// every command in its tendon's range with every tension at least the
// minimum (SafetyEnvelope::Check), and no tendon faster than max_rate
// between two consecutive commands. The gate promises this by construction
// (safety_gate.h); experiments and end-to-end tests check the promise on
// what went out on the wire.

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "libs/control/safety_gate.h"

namespace shapesense {

struct LimitViolations {
  int range_or_tension = 0;  // outside a range, or a tension below the minimum
  int rate = 0;              // a tendon moved faster than max_rate
  int malformed = 0;         // wrong number of tendons, or not finite
  int total() const { return range_or_tension + rate + malformed; }
};

class LimitAudit {
 public:
  explicit LimitAudit(SafetyEnvelope envelope) : envelope_(std::move(envelope)) {}

  // A command sent at `utime` (µs, the sender's clock); the rate is checked
  // against the previous command.
  void Check(const Eigen::VectorXd& command, int64_t utime);

  const LimitViolations& violations() const { return violations_; }
  int64_t commands() const { return commands_; }
  // What the first violation was ("" when none).
  const std::string& first_violation() const { return first_; }

 private:
  void Record(int* counter, const std::string& what);

  SafetyEnvelope envelope_;
  LimitViolations violations_;
  int64_t commands_ = 0;
  Eigen::VectorXd previous_;
  int64_t previous_utime_ = -1;
  std::string first_;
};

}  // namespace shapesense
