// The typed LCM bus, in process over memq://: messages arrive decoded,
// malformed ones are counted and never reach a handler, a throwing handler
// is contained.
#include "runtime/lcm/lcm_bus.h"

#include <gtest/gtest.h>

#include "runtime/lcm/channels.h"
#include "runtime/lcm/service_status.h"
#include "shapesense/shape_t.hpp"
#include "shapesense/voxel_cloud_t.hpp"

namespace shapesense {
namespace {

// Handles until `done` or 100 rounds of 10 ms.
template <class Done>
void HandleUntil(LcmBus& bus, Done done) {
  for (int i = 0; i < 100 && !done(); ++i) bus.Handle(10);
}

TEST(LcmBusTest, DeliversTypedMessages) {
  LcmBus bus("memq://");
  std::vector<int64_t> seen;
  bus.Subscribe<shape_t>(channels::kShape,
                         [&](const shape_t& shape, const std::string& channel, int64_t) {
                           EXPECT_EQ(channel, channels::kShape);
                           seen.push_back(shape.trigger_seq);
                         });
  for (int64_t i = 0; i < 3; ++i) {
    shape_t shape{};
    shape.trigger_seq = i;
    ASSERT_TRUE(bus.Publish(channels::kShape, shape));
  }
  HandleUntil(bus, [&] { return seen.size() == 3; });
  EXPECT_EQ(seen, (std::vector<int64_t>{0, 1, 2}));
  EXPECT_EQ(bus.Rejected(), 0);
}

TEST(LcmBusTest, MalformedMessagesAreCountedNotDelivered) {
  LcmBus bus("memq://");
  int delivered = 0;
  bus.Subscribe<shape_t>(channels::kShape,
                         [&](const shape_t&, const std::string&, int64_t) { ++delivered; });
  voxel_cloud_t wrong_type{};
  bus.Publish(channels::kShape, wrong_type);
  HandleUntil(bus, [&] { return bus.Rejected() == 1; });
  EXPECT_EQ(bus.Rejected(), 1);
  EXPECT_EQ(delivered, 0);
  EXPECT_NE(bus.LastRejection().find("not a valid shape_t"), std::string::npos)
      << bus.LastRejection();
}

TEST(LcmBusTest, ATruncatedMessageIsRejected) {
  LcmBus bus("memq://");
  int delivered = 0;
  bus.Subscribe<shape_t>(channels::kShape,
                         [&](const shape_t&, const std::string&, int64_t) { ++delivered; });
  // A message of the right type cut short: publish its first bytes raw
  // through a second subscription-free publisher on the same provider.
  shape_t shape{};
  shape.num_points = 2;
  shape.centerline = {{0, 0, 0}, {1, 1, 1}};
  shape.arc_length = {0, 1.7};
  shape.curvature = {0, 0};
  std::vector<uint8_t> bytes(static_cast<size_t>(shape.getEncodedSize()));
  shape.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  struct Truncated {
    std::vector<uint8_t> bytes;
    int encode(void* buf, int offset, int max) const {
      if (max < static_cast<int>(bytes.size())) return -1;
      std::copy(bytes.begin(), bytes.end(), static_cast<uint8_t*>(buf) + offset);
      return static_cast<int>(bytes.size());
    }
    int getEncodedSize() const { return static_cast<int>(bytes.size()); }
  };
  bus.Publish(channels::kShape, Truncated{std::vector<uint8_t>(bytes.begin(), bytes.begin() + 40)});
  HandleUntil(bus, [&] { return bus.Rejected() == 1; });
  EXPECT_EQ(bus.Rejected(), 1);
  EXPECT_EQ(delivered, 0);
}

TEST(LcmBusTest, AThrowingHandlerIsContainedAndCounted) {
  LcmBus bus("memq://");
  int calls = 0;
  bus.Subscribe<shape_t>(channels::kShape, [&](const shape_t&, const std::string&, int64_t) {
    ++calls;
    throw std::runtime_error("boom");
  });
  bus.Publish(channels::kShape, shape_t{});
  bus.Publish(channels::kShape, shape_t{});
  HandleUntil(bus, [&] { return calls == 2; });
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(bus.HandlerErrors(), 2);
}

TEST(ServiceStatusTest, PublishesAtOneHertzWithTheCounters) {
  LcmBus bus("memq://");
  std::vector<service_status_t> statuses;
  bus.Subscribe<service_status_t>(
      channels::Status("carving"),
      [&](const service_status_t& s, const std::string&, int64_t) { statuses.push_back(s); });
  ServiceStatus status("carving");
  status.Received(10);
  status.Dropped(2);
  status.Error("frame 7: camera cam1 missing");
  status.MaybePublish(bus, 1'000'000);
  status.MaybePublish(bus, 1'500'000);  // too soon: not published
  status.Received(5);
  status.MaybePublish(bus, 2'000'000);
  HandleUntil(bus, [&] { return statuses.size() == 2; });
  ASSERT_EQ(statuses.size(), 2u);
  EXPECT_EQ(statuses[0].received, 10);
  EXPECT_EQ(statuses[0].dropped, 2);
  EXPECT_EQ(statuses[0].errors, 1);
  EXPECT_EQ(statuses[0].last_error, "frame 7: camera cam1 missing");
  EXPECT_EQ(statuses[1].received, 15);
  EXPECT_NEAR(statuses[1].input_rate_hz, 5.0, 1e-3);
  EXPECT_EQ(statuses[1].header.seq, 1);
}

}  // namespace
}  // namespace shapesense
