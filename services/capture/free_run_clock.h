#pragma once

#include <algorithm>
#include <chrono>
#include <thread>

namespace shapesense {

// The frame clock of a camera that runs free at a set rate (replay and
// simulated backends). Late frames are delivered late, not skipped; after a
// stall longer than a period the schedule restarts from now instead of
// bursting to catch up.
class FreeRunClock {
 public:
  using Clock = std::chrono::steady_clock;

  explicit FreeRunClock(double rate_hz)
      : period_(std::chrono::duration_cast<Clock::duration>(
            std::chrono::duration<double>(1.0 / rate_hz))) {}

  void Restart() { next_due_ = Clock::now(); }

  // Sleeps until the next frame is due and returns true, or sleeps `timeout`
  // and returns false when the next frame is due later than that.
  bool WaitNext(std::chrono::milliseconds timeout) {
    if (next_due_ > Clock::now() + timeout) {
      std::this_thread::sleep_for(timeout);
      return false;
    }
    std::this_thread::sleep_until(next_due_);
    next_due_ = std::max(next_due_ + period_, Clock::now() - period_);
    return true;
  }

 private:
  const Clock::duration period_;
  Clock::time_point next_due_ = Clock::now();
};

}  // namespace shapesense
