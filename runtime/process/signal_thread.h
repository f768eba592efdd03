#pragma once

// How the programs take signals. Two ways, for two needs:
//  - StopFlagOnSignals: SIGINT and SIGTERM set one lock-free flag, the only
//    thing a handler may safely do. For programs whose one signal is
//    "stop" (the services, the demo); callable at any time, also after
//    threads exist (LCM starts its reader thread in its constructor).
//  - SignalThread: signals taken on a thread of their own instead of in a
//    handler, so that their code runs as ordinary code (no async-signal-
//    safety rules, no globals for it to reach) and a program's state stays
//    in its main. For programs that take signals as commands (the rig-sim's
//    SIGUSR1/SIGUSR2 faults); it must be built first in main, before any
//    thread, so that every thread inherits the blocked signals.
#include <atomic>
#include <csignal>
#include <functional>
#include <initializer_list>
#include <thread>

namespace shapesense {

// A flag that SIGINT and SIGTERM set (installs the handlers on first use);
// a service's main passes it as `stop`.
const std::atomic<bool>& StopFlagOnSignals();

class SignalThread {
 public:
  // Blocks `signals` in the calling thread, and so in every thread it starts
  // afterwards: construct it first in main. `on_signal` runs on the signal
  // thread for each one that arrives.
  SignalThread(std::initializer_list<int> signals, std::function<void(int)> on_signal);
  // Stops the thread (within its 100 ms wait) and unblocks the signals.
  ~SignalThread();
  SignalThread(const SignalThread&) = delete;
  SignalThread& operator=(const SignalThread&) = delete;

 private:
  void Run();

  sigset_t signals_{};
  std::function<void(int)> on_signal_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

}  // namespace shapesense
