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

  // A command sent at `utime` (µs, the sender's clock) with the sender's
  // step number `seq` (-1: unknown); the rate is checked against the
  // previous command. Commands the audit did not see (lost on the way to
  // it: `seq` skipped) each had a step of their own, so the step across the
  // gap may be that many steps long.
  void Check(const Eigen::VectorXd& command, int64_t utime, int64_t seq = -1);

  const LimitViolations& violations() const { return violations_; }
  int64_t commands() const { return commands_; }
  // Commands skipped by `seq`: sent, but never seen by the audit.
  int64_t missed() const { return missed_; }
  // What the first violation was ("" when none).
  const std::string& first_violation() const { return first_; }

 private:
  void Record(int* counter, const std::string& what);

  SafetyEnvelope envelope_;
  LimitViolations violations_;
  int64_t commands_ = 0;
  Eigen::VectorXd previous_;
  int64_t previous_utime_ = -1;
  int64_t previous_seq_ = -1;
  int64_t missed_ = 0;
  std::string first_;
};

}  // namespace shapesense
