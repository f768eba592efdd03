#include "runtime/lcm/service_loop.h"

#include <malloc.h>
#include <poll.h>

#include <cerrno>
#include <chrono>
#include <thread>

namespace shapesense {

void RunBusLoop(LcmBus& bus, const std::atomic<bool>& stop, double duration_s,
                const std::function<void(int64_t now_utime)>& poll, SystemdNotifier& supervisor) {
  RunBusLoop(std::vector<LcmBus*>{&bus}, stop, duration_s, poll, supervisor);
}

void RunBusLoop(const std::vector<LcmBus*>& buses, const std::atomic<bool>& stop, double duration_s,
                const std::function<void(int64_t now_utime)>& poll, SystemdNotifier& supervisor) {
  using Clock = std::chrono::steady_clock;
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(duration_s));
  std::vector<pollfd> waiting;
  std::vector<LcmBus*> owner;  // of each descriptor
  for (LcmBus* bus : buses) {
    for (const int descriptor : bus->FileDescriptors()) {
      waiting.push_back({descriptor, POLLIN, 0});
      owner.push_back(bus);
    }
  }
  while (!stop.load() && (duration_s <= 0 || Clock::now() < end)) {
    supervisor.Watchdog();
    const int ready = ::poll(waiting.data(), waiting.size(), 20);
    bool failed = ready < 0 && errno != EINTR;
    for (size_t i = 0; ready > 0 && i < waiting.size(); ++i) {
      if ((waiting[i].revents & POLLIN) != 0) failed |= owner[i]->Handle(0) < 0;
    }
    // An LCM error (e.g. a socket gone) must not turn the loop into a spin.
    if (failed) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    poll(NowUtime());
  }
  supervisor.Stopping();
}

void KeepFreedMemoryForReuse() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
}

}  // namespace shapesense
