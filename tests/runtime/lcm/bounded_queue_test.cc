#include "runtime/lcm/bounded_queue.h"

#include <gtest/gtest.h>

#include <thread>

namespace shapesense {
namespace {

using std::chrono::milliseconds;

TEST(BoundedQueueTest, DropsTheOldestWhenFullAndCountsIt) {
  BoundedQueue<int> queue(3);
  for (int i = 0; i < 5; ++i) queue.Push(i);
  EXPECT_EQ(queue.Dropped(), 2);
  EXPECT_EQ(queue.Size(), 3u);
  for (int expected : {2, 3, 4}) EXPECT_EQ(queue.Pop(milliseconds(0)), expected);
  EXPECT_FALSE(queue.Pop(milliseconds(1)).has_value());
}

TEST(BoundedQueueTest, PopWaitsForAPushFromAnotherThread) {
  BoundedQueue<int> queue(2);
  std::thread producer([&] {
    std::this_thread::sleep_for(milliseconds(20));
    queue.Push(42);
  });
  EXPECT_EQ(queue.Pop(milliseconds(5000)), 42);
  producer.join();
}

TEST(BoundedQueueTest, CloseWakesAWaitingConsumer) {
  BoundedQueue<int> queue(2);
  std::thread closer([&] {
    std::this_thread::sleep_for(milliseconds(20));
    queue.Close();
  });
  EXPECT_FALSE(queue.Pop(milliseconds(5000)).has_value());
  closer.join();
}

}  // namespace
}  // namespace shapesense
