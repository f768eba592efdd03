#include "runtime/lcm/clock_offsets.h"

#include <algorithm>

namespace shapesense {

void ClockOffsets::Observe(const std::string& host, int64_t send_utime, int64_t receive_utime) {
  const int64_t difference = receive_utime - send_utime;
  const std::lock_guard lock(mutex_);
  Estimate& estimate = hosts_[host];
  if (estimate.samples == 0) {
    estimate.window_start_utime = receive_utime;
    estimate.current_min = difference;
  } else if (receive_utime - estimate.window_start_utime >= half_window_us_) {
    estimate.previous_min = estimate.current_min;
    estimate.has_previous = true;
    estimate.current_min = difference;
    estimate.window_start_utime = receive_utime;
  } else {
    estimate.current_min = std::min(estimate.current_min, difference);
  }
  ++estimate.samples;
  estimate.last_receive_utime = receive_utime;
}

int64_t ClockOffsets::SmallestDelay(const Estimate& estimate) {
  return estimate.has_previous ? std::min(estimate.current_min, estimate.previous_min)
                               : estimate.current_min;
}

std::vector<HostClockOffset> ClockOffsets::Snapshot() const {
  const std::lock_guard lock(mutex_);
  std::vector<HostClockOffset> offsets;
  for (const auto& [host, estimate] : hosts_) {
    offsets.push_back(
        {host, -SmallestDelay(estimate), estimate.samples, estimate.last_receive_utime});
  }
  return offsets;
}

std::optional<int64_t> ClockOffsets::OffsetOf(const std::string& host) const {
  const std::lock_guard lock(mutex_);
  const auto found = hosts_.find(host);
  if (found == hosts_.end()) return std::nullopt;
  return -SmallestDelay(found->second);
}

}  // namespace shapesense
