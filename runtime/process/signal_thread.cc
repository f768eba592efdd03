#include "runtime/process/signal_thread.h"

#include <pthread.h>

#include <ctime>

namespace shapesense {
namespace {

std::atomic<bool> signalled{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void OnStopSignal(int) { signalled.store(true); }

}  // namespace

const std::atomic<bool>& StopFlagOnSignals() {
  static const bool installed = [] {
    std::signal(SIGINT, OnStopSignal);
    std::signal(SIGTERM, OnStopSignal);
    return true;
  }();
  (void)installed;
  return signalled;
}

SignalThread::SignalThread(std::initializer_list<int> signals, std::function<void(int)> on_signal)
    : on_signal_(std::move(on_signal)) {
  sigemptyset(&signals_);
  for (const int signal : signals) sigaddset(&signals_, signal);
  pthread_sigmask(SIG_BLOCK, &signals_, nullptr);
  thread_ = std::thread([this] { Run(); });
}

SignalThread::~SignalThread() {
  done_ = true;
  thread_.join();
  pthread_sigmask(SIG_UNBLOCK, &signals_, nullptr);
}

// A bounded wait, so that the destructor needs no signal of its own to end
// the thread.
void SignalThread::Run() {
  constexpr timespec kWait{0, 100'000'000};
  while (!done_) {
    const int signal = sigtimedwait(&signals_, nullptr, &kWait);
    if (signal > 0) on_signal_(signal);
  }
}

}  // namespace shapesense
