#pragma once

// Signals taken on a thread of their own instead of in a handler: the
// handler's code runs as ordinary code (no async-signal-safety rules, no
// globals for it to reach), and a program's state stays in its main.
#include <atomic>
#include <csignal>
#include <functional>
#include <initializer_list>
#include <thread>

namespace shapesense {

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
