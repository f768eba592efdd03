#pragma once

// The main loop every LCM service shares: handle messages on one thread,
// and give the service the time for its timeouts and 1 Hz status.
#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include "runtime/lcm/lcm_bus.h"
#include "runtime/process/systemd_notify.h"

namespace shapesense {

// Handles `bus` until `stop` is set or `duration_s` has passed (0: no
// limit), calling `poll(now_utime)` after every message and at least every
// 20 ms. Callbacks and `poll` all run on the calling thread. Every iteration
// pings `supervisor`'s watchdog (so a callback or `poll` that hangs stops
// the pings, and systemd restarts the service); STOPPING=1 as it returns.
void RunBusLoop(LcmBus& bus, const std::atomic<bool>& stop, double duration_s,
                const std::function<void(int64_t now_utime)>& poll, SystemdNotifier& supervisor);
// The same over several buses (a service's main bus and its image buses),
// each handled as its messages arrive.
void RunBusLoop(const std::vector<LcmBus*>& buses, const std::atomic<bool>& stop, double duration_s,
                const std::function<void(int64_t now_utime)>& poll, SystemdNotifier& supervisor);

// Keeps freed memory in the process instead of returning it to the kernel:
// a service allocates image-sized buffers (~1 MB) for every frame-set, and
// glibc would otherwise map them fresh each time, so every frame-set paid
// ~1000 page faults and their zeroing (measured with the latency bench:
// this halves the shape service's CPU per frame-set). Call first in main.
void KeepFreedMemoryForReuse();

}  // namespace shapesense
