// SystemdNotifier (runtime/process/systemd_notify.h) against a socket the
// test owns as systemd would: nothing without NOTIFY_SOCKET, the watchdog
// period read from the environment (and left there), READY=1 with a status,
// watchdog pings at most every half period, STOPPING=1 once. Then the
// services' loop, RunBusLoop over a memq:// bus, as supervised: ready, pings
// while it runs, none once it hangs, pings again when it recovers, STOPPING=1
// on a stop. Bounds are on counts, and every wait is bounded.
#include "runtime/process/systemd_notify.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <thread>

#include "runtime/lcm/service_loop.h"
#include "tests/runtime/process/notify_socket.h"

namespace shapesense {
namespace {

using std::chrono::milliseconds;
using testing::NotifySocket;

constexpr long kWatchdogUsec = 200'000;  // systemd would then expect a ping every 200 ms
constexpr milliseconds kPeriod(kWatchdogUsec / 1000);

TEST(SystemdNotifier, DoesNothingWithoutNotifySocket) {
  ::unsetenv("NOTIFY_SOCKET");
  ::setenv("WATCHDOG_USEC", "200000", 1);
  SystemdNotifier notifier;
  EXPECT_FALSE(notifier.enabled());
  EXPECT_EQ(notifier.watchdog_timeout().count(), 0);
  notifier.Ready("ready");
  notifier.Watchdog();
  notifier.Stopping();
  ::unsetenv("WATCHDOG_USEC");
}

TEST(SystemdNotifier, ReadsTheWatchdogForThisProcessAndLeavesTheEnvironment) {
  const NotifySocket socket(kWatchdogUsec);
  EXPECT_EQ(SystemdNotifier().watchdog_timeout(), std::chrono::microseconds(kWatchdogUsec));
  ::setenv("WATCHDOG_PID", std::to_string(getpid()).c_str(), 1);
  EXPECT_EQ(SystemdNotifier().watchdog_timeout(), std::chrono::microseconds(kWatchdogUsec));
  // Another process's watchdog: not this one's to ping.
  ::setenv("WATCHDOG_PID", "1", 1);
  EXPECT_EQ(SystemdNotifier().watchdog_timeout().count(), 0);
  EXPECT_NE(std::getenv("NOTIFY_SOCKET"), nullptr);
  EXPECT_NE(std::getenv("WATCHDOG_USEC"), nullptr);
}

TEST(SystemdNotifier, SaysReadyWithItsStatus) {
  NotifySocket socket;
  SystemdNotifier notifier;
  EXPECT_TRUE(notifier.enabled());
  notifier.Ready("carving frame-sets");
  ASSERT_TRUE(socket.WaitFor("READY=1", milliseconds(5000))) << socket.Transcript();
  socket.Drain();
  EXPECT_NE(socket.Transcript().find("STATUS=carving frame-sets"), std::string::npos)
      << socket.Transcript();
}

TEST(SystemdNotifier, WithoutAWatchdogPeriodSendsNoPing) {
  NotifySocket socket;  // no WATCHDOG_USEC
  SystemdNotifier notifier;
  notifier.Watchdog();
  notifier.Status("still here");
  ASSERT_TRUE(socket.WaitFor("STATUS=still here", milliseconds(5000)));
  EXPECT_EQ(socket.Transcript(), "STATUS=still here\n");
}

TEST(SystemdNotifier, PingsAtMostEveryHalfPeriodHoweverOftenCalled) {
  NotifySocket socket(kWatchdogUsec);
  SystemdNotifier notifier;
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < milliseconds(1000)) {
    notifier.Watchdog();
    std::this_thread::sleep_for(milliseconds(1));
  }
  socket.Drain();
  const auto pings = std::count(socket.lines().begin(), socket.lines().end(), "WATCHDOG=1");
  // One at once, then one per 100 ms: 11 at most in 1 s; at least 2 however slow the machine.
  EXPECT_GE(pings, 2);
  EXPECT_LE(pings, 11);
}

TEST(SystemdNotifier, AnUnhealthyWorkerStopsThePingsUntilItRecovers) {
  NotifySocket socket(kWatchdogUsec);
  SystemdNotifier notifier;
  bool healthy = false;
  notifier.SetHealthCheck([&] { return healthy; });
  const auto run_for = [&](milliseconds span) {
    const auto start = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - start < span) {
      notifier.Watchdog();
      std::this_thread::sleep_for(milliseconds(1));
    }
  };
  run_for(milliseconds(500));  // 2.5 watchdog periods
  notifier.Status("sick");
  ASSERT_TRUE(socket.WaitFor("STATUS=sick", milliseconds(5000)));
  EXPECT_EQ(socket.Transcript(), "STATUS=sick\n") << "no ping while unhealthy";
  healthy = true;
  run_for(milliseconds(10));
  EXPECT_TRUE(socket.WaitFor("WATCHDOG=1", milliseconds(5000)));
}

TEST(SystemdNotifier, SaysStoppingOnce) {
  NotifySocket socket;
  SystemdNotifier notifier;
  notifier.Stopping();
  notifier.Stopping();
  notifier.Status("end");
  ASSERT_TRUE(socket.WaitFor("STATUS=end", milliseconds(5000)));
  EXPECT_EQ(socket.Transcript(), "STOPPING=1\nSTATUS=end\n");
}

// A service's loop on a thread of its own, whose poll can be made to hang:
// always stopped and joined, also when an assertion fails.
class HangableLoop {
 public:
  explicit HangableLoop(SystemdNotifier& supervisor)
      : thread_([this, &supervisor] {
          supervisor.Ready("test loop");
          RunBusLoop(
              bus_, stop_, 0.0, [this](int64_t) { Poll(); }, supervisor);
        }) {}
  ~HangableLoop() {
    Release();
    Stop();
    thread_.join();
  }
  HangableLoop(const HangableLoop&) = delete;
  HangableLoop& operator=(const HangableLoop&) = delete;

  // Makes the next poll block; true once it does (bounded wait).
  bool Hang() {
    hang_ = true;
    for (int i = 0; i < 500 && !hanging_; ++i) std::this_thread::sleep_for(milliseconds(10));
    return hanging_;
  }
  void Release() { hang_ = false; }
  void Stop() { stop_ = true; }

 private:
  void Poll() {
    while (hang_) {
      hanging_ = true;
      std::this_thread::sleep_for(milliseconds(5));
    }
    hanging_ = false;
  }

  LcmBus bus_{"memq://"};
  std::atomic<bool> stop_{false};
  std::atomic<bool> hang_{false};
  std::atomic<bool> hanging_{false};
  std::thread thread_;
};

TEST(SupervisedBusLoop, PingsWhileItRunsNotWhenItHangsAndSaysStopping) {
  NotifySocket socket(kWatchdogUsec);
  ::setenv("WATCHDOG_PID", std::to_string(getpid()).c_str(), 1);
  SystemdNotifier supervisor;
  HangableLoop loop(supervisor);
  ASSERT_TRUE(socket.WaitFor("READY=1", milliseconds(5000))) << socket.Transcript();
  EXPECT_GE(socket.Count("WATCHDOG=1", milliseconds(2000)), 2) << socket.Transcript();

  ASSERT_TRUE(loop.Hang());
  socket.Drain();  // what was sent before the loop hung
  EXPECT_EQ(socket.Count("WATCHDOG=1", 3 * kPeriod + milliseconds(100)), 0)
      << "a hung loop must not ping the watchdog";

  loop.Release();
  EXPECT_TRUE(socket.WaitFor("WATCHDOG=1", milliseconds(5000))) << "pings again once it recovers";
  loop.Stop();
  EXPECT_TRUE(socket.WaitFor("STOPPING=1", milliseconds(5000))) << socket.Transcript();
}

}  // namespace
}  // namespace shapesense
