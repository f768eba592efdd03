#pragma once

// This host's clock against every other host's, estimated from the traffic
// a program already receives: a message sent at t_send on host H's clock and
// received at t_recv on ours gives t_recv - t_send = (ours - H's) + transit.
// Transit is never negative, so over many messages the smallest difference
// is the offset plus the shortest transit (tens of µs on one switch): the
// offset of H's clock from ours is -min(t_recv - t_send). The minimum is
// kept over a sliding window (two half windows), so that it follows a clock
// that drifts or is stepped, and a single slow message never moves it.
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace shapesense {

struct HostClockOffset {
  std::string host;
  // H's clock minus ours, µs (positive: H's clock is ahead of ours). An
  // upper bound in error by the shortest transit seen.
  int64_t offset_us = 0;
  int64_t samples = 0;             // messages observed from H
  int64_t last_receive_utime = 0;  // our clock
};

class ClockOffsets {
 public:
  explicit ClockOffsets(int64_t window_us = 10'000'000) : half_window_us_(window_us / 2) {}

  // One message from `host`, published at `send_utime` (its clock) and
  // received at `receive_utime` (ours). Thread-safe.
  void Observe(const std::string& host, int64_t send_utime, int64_t receive_utime);

  // Every host heard from, sorted by name. Thread-safe.
  std::vector<HostClockOffset> Snapshot() const;
  // `host`'s offset (its clock minus ours, µs), nullopt when not heard from
  // (this host among them). Thread-safe.
  std::optional<int64_t> OffsetOf(const std::string& host) const;

 private:
  struct Estimate {
    int64_t window_start_utime = 0;
    int64_t current_min = 0;   // min(receive - send) over the current half window
    int64_t previous_min = 0;  // over the half window before
    bool has_previous = false;
    int64_t samples = 0;
    int64_t last_receive_utime = 0;
  };
  static int64_t SmallestDelay(const Estimate& estimate);

  int64_t half_window_us_;
  mutable std::mutex mutex_;
  std::map<std::string, Estimate> hosts_;
};

}  // namespace shapesense
