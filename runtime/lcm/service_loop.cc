#include "runtime/lcm/service_loop.h"

#include <malloc.h>

#include <chrono>
#include <csignal>
#include <thread>

namespace shapesense {
namespace {

std::atomic<bool> signalled{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void OnStopSignal(int) { signalled.store(true); }

}  // namespace

void RunBusLoop(LcmBus& bus, const std::atomic<bool>& stop, double duration_s,
                const std::function<void(int64_t now_utime)>& poll) {
  using Clock = std::chrono::steady_clock;
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(duration_s));
  while (!stop.load() && (duration_s <= 0 || Clock::now() < end)) {
    // An LCM error (e.g. a socket gone) must not turn the loop into a spin.
    if (bus.Handle(20) < 0) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    poll(NowUtime());
  }
}

void KeepFreedMemoryForReuse() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
}

const std::atomic<bool>& StopFlagOnSignals() {
  static const bool installed = [] {
    std::signal(SIGINT, OnStopSignal);
    std::signal(SIGTERM, OnStopSignal);
    return true;
  }();
  (void)installed;
  return signalled;
}

}  // namespace shapesense
