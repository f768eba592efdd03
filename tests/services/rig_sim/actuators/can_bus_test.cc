// The in-memory CAN bus behaves as a wire does for the master and the drives:
// every other endpoint gets every frame, in order; receive waits are bounded;
// a cut link fails sends and receives; full queues drop their oldest frame.
#include "services/rig_sim/actuators/in_memory_can_bus.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>
#include <thread>

namespace shapesense {
namespace {

using std::chrono::microseconds;
using ::testing::HasSubstr;

CanFrame RandomFrame(std::mt19937& rng) {
  CanFrame frame;
  frame.id = rng() & 0x7FF;
  frame.size = static_cast<uint8_t>(rng() % 9);
  for (size_t i = 0; i < frame.size; ++i) frame.data[i] = static_cast<uint8_t>(rng());
  return frame;
}

TEST(InMemoryCanBusTest, EveryOtherEndpointGetsEveryFrameInOrder) {
  InMemoryCanNetwork network;
  auto a = network.Attach("a");
  auto b = network.Attach("b");
  auto c = network.Attach("c");
  std::mt19937 rng(51);
  std::vector<CanFrame> sent;
  for (int i = 0; i < 100; ++i) {
    sent.push_back(RandomFrame(rng));
    a->Send(sent.back());
  }
  for (CanBus* receiver : {b.get(), c.get()}) {
    for (const CanFrame& frame : sent) EXPECT_EQ(receiver->Receive(microseconds(0)), frame);
    EXPECT_FALSE(receiver->Receive(microseconds(0)));
  }
  EXPECT_FALSE(a->Receive(microseconds(1000))) << "a sender does not hear itself";
  EXPECT_EQ(a->name(), "memory:a");
}

TEST(InMemoryCanBusTest, AReceiveWaitsForAFrameFromAnotherThread) {
  InMemoryCanNetwork network;
  auto master = network.Attach("master");
  auto drive = network.Attach("drive");
  std::thread sender([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    drive->Send(CanFrame{0x701, 1, {0x05}});
  });
  const std::optional<CanFrame> frame = master->Receive(microseconds(5'000'000));
  sender.join();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->id, 0x701u);
}

TEST(InMemoryCanBusTest, ACutLinkFailsSendsAndReceivesUntilRestored) {
  InMemoryCanNetwork network;
  auto master = network.Attach("master");
  auto drive = network.Attach("drive");
  drive->Send(CanFrame{0x701, 1, {0x05}});
  network.SetLinkUp("master", false);
  try {
    master->Send(CanFrame{0x080, 0, {}});
    FAIL() << "expected CanBusError";
  } catch (const CanBusError& e) {
    EXPECT_THAT(e.what(), HasSubstr("memory:master: link down"));
  }
  EXPECT_THROW(master->Receive(microseconds(0)), CanBusError);
  drive->Send(CanFrame{0x701, 1, {0x05}});  // lost on the cut cable
  network.SetLinkUp("master", true);
  EXPECT_FALSE(master->Receive(microseconds(0))) << "nothing from while the cable was cut";
  master->Send(CanFrame{0x080, 0, {}});
  EXPECT_EQ(drive->Receive(microseconds(0))->id, 0x080u);
}

TEST(InMemoryCanBusTest, AFullQueueDropsItsOldestFrames) {
  InMemoryCanNetwork network(4);
  auto a = network.Attach("a");
  auto b = network.Attach("b");
  for (uint32_t id = 1; id <= 6; ++id) a->Send(CanFrame{id, 0, {}});
  EXPECT_EQ(network.overruns(), 2);
  EXPECT_EQ(b->Receive(microseconds(0))->id, 3u);
}

}  // namespace
}  // namespace shapesense
