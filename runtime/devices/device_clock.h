#pragma once

// The clocks the drivers use: a steady clock for timeouts and the epoch for
// timestamps (LCM's utime).

#include <chrono>
#include <cstdint>

#include "runtime/host_clock.h"

namespace shapesense {

// Monotonic µs, for deadlines and durations.
inline int64_t SteadyMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// µs since the epoch on this host's clock, for timestamps.
inline int64_t EpochMicros() { return HostUtime(); }

inline int64_t SecondsToMicros(double seconds) { return static_cast<int64_t>(seconds * 1e6); }

}  // namespace shapesense
