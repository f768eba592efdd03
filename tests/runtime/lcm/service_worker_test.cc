// The service worker says when one job has held it too long, so that a
// service's watchdog stops pinging while its worker hangs.
#include "runtime/lcm/service_worker.h"

#include <gtest/gtest.h>

#include <future>
#include <thread>

namespace shapesense {
namespace {

TEST(ServiceWorkerTest, AJobThatHangsIsSeenAndAFinishedOneIsNot) {
  ServiceStatus status("test");
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::promise<void> started;
  ServiceWorker<int> worker(
      2, status, "job", [](const int&) { return std::string("job"); },
      [&](int&) {
        started.set_value();
        released.wait();
        status.Published();
      });
  EXPECT_FALSE(worker.BusyLongerThan(std::chrono::microseconds(0))) << "idle";
  worker.Push(1);
  started.get_future().wait();
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  EXPECT_TRUE(worker.BusyLongerThan(std::chrono::milliseconds(10)));
  EXPECT_FALSE(worker.BusyLongerThan(std::chrono::hours(1)));
  release.set_value();
  for (int i = 0; i < 500 && status.published() == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(status.published(), 1);
  // Published is counted inside the job: give the worker its return.
  for (int i = 0; i < 500 && worker.BusyLongerThan(std::chrono::microseconds(0)); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_FALSE(worker.BusyLongerThan(std::chrono::microseconds(0)));
}

}  // namespace
}  // namespace shapesense
