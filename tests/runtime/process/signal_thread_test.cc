// SignalThread: signals sent to the process reach its callback, as ordinary
// code on its own thread, and the thread ends by itself with its owner.
#include "runtime/process/signal_thread.h"

#include <gtest/gtest.h>
#include <signal.h>

#include <atomic>
#include <chrono>
#include <thread>

namespace shapesense {
namespace {

// Waits (bounded) until `count` reaches `expected`.
bool WaitFor(const std::atomic<int>& count, int expected) {
  for (int i = 0; i < 1000 && count.load() < expected; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return count.load() >= expected;
}

TEST(SignalThreadTest, EachSignalSentToTheProcessReachesTheCallbackByNumber) {
  std::atomic<int> usr1{0};
  std::atomic<int> usr2{0};
  {
    const SignalThread signals({SIGUSR1, SIGUSR2}, [&](int signal) {
      if (signal == SIGUSR1) ++usr1;
      if (signal == SIGUSR2) ++usr2;
    });
    kill(getpid(), SIGUSR1);
    ASSERT_TRUE(WaitFor(usr1, 1));
    kill(getpid(), SIGUSR2);
    ASSERT_TRUE(WaitFor(usr2, 1));
    kill(getpid(), SIGUSR1);
    ASSERT_TRUE(WaitFor(usr1, 2));
  }
  EXPECT_EQ(usr1.load(), 2);
  EXPECT_EQ(usr2.load(), 1);
  // Unblocked again afterwards: an ignored signal now passes by.
  sigset_t blocked;
  pthread_sigmask(SIG_BLOCK, nullptr, &blocked);
  EXPECT_EQ(sigismember(&blocked, SIGUSR1), 0);
}

}  // namespace
}  // namespace shapesense
