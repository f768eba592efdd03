// The rig's two LCM networks, its channel prefix and its clocks, over real
// UDP multicast in a private network namespace: which channel takes which
// network, what the rig network refuses, rigs that share a network without
// hearing each other, every message naming its host, and the clock offsets
// estimated from the traffic.
#include <gtest/gtest.h>

#include <unistd.h>

#include <atomic>

#include "runtime/lcm/channel_networks.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/clock_offsets.h"
#include "runtime/lcm/image_buses.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/lcm/lcm_url.h"
#include "runtime/lcm/service_status.h"
#include "shapesense/image_t.hpp"
#include "shapesense/shape_t.hpp"
#include "shapesense/voxel_cloud_t.hpp"
#include "tests/runtime/lcm/temporary_key_file.h"
#include "tests/support/network_test.h"

namespace shapesense {
namespace {

constexpr const char* kRig = "udpm://239.255.78.1:7801?ttl=1";
constexpr const char* kLocal = "udpm://239.255.78.1:7811?ttl=0";

template <class Done>
void HandleUntil(std::initializer_list<LcmBus*> buses, Done done, int rounds = 100) {
  for (int i = 0; i < rounds && !done(); ++i) {
    for (LcmBus* bus : buses) bus->Handle(5);
  }
}

// The rig network leaves the host: every bus holds the rig key.
const test_keys::TemporaryKeyFile& RigKey() {
  static const test_keys::TemporaryKeyFile key;
  return key;
}

LcmBusOptions Options(const std::string& url, const std::string& local = {},
                      const std::string& prefix = {}, const std::string& host = {}) {
  LcmBusOptions options;
  options.auth.key_files = {RigKey().path()};
  options.url = url;
  options.local_url = local.empty() ? url : local;
  options.prefix = prefix;
  options.host = host;
  return options;
}

TEST(ChannelNetworksTest, ImagesStayLocalAndEverythingElseTakesTheRigNetwork) {
  const ChannelNetworks networks;
  EXPECT_EQ(networks.Of(channels::Image("cam0")), Network::kLocal);
  EXPECT_EQ(networks.Of(channels::Silhouette("cam2")), Network::kLocal);
  for (const char* channel : {channels::kSilhouettes, channels::kVoxels, channels::kShape,
                              channels::kTruth, channels::kTarget, channels::kTendonCommand}) {
    EXPECT_EQ(networks.Of(channel), Network::kRig) << channel;
  }
  EXPECT_EQ(networks.Of(channels::Status("carving")), Network::kRig);
  // Patterns: listened for locally only when they may match a local channel.
  EXPECT_TRUE(networks.MayBeLocal(channels::kImagePattern));
  EXPECT_TRUE(networks.MayBeLocal(".*"));
  EXPECT_FALSE(networks.MayBeLocal(channels::kStatusPattern));
}

TEST(ChannelNetworksTest, OverridesComeFirstAndParseBackFromText) {
  const auto routes = ChannelNetworks::Parse("SHAPESENSE_VOXELS=local,SHAPESENSE_IMAGE_cam9=rig");
  ASSERT_EQ(routes.size(), 2u);
  EXPECT_EQ(ChannelNetworks::Format(routes), "SHAPESENSE_VOXELS=local,SHAPESENSE_IMAGE_cam9=rig");
  const ChannelNetworks networks(routes);
  EXPECT_EQ(networks.Of(channels::kVoxels), Network::kLocal);
  EXPECT_EQ(networks.Of(channels::Image("cam9")), Network::kRig);
  EXPECT_EQ(networks.Of(channels::Image("cam0")), Network::kLocal);
  EXPECT_THROW(ChannelNetworks::Parse("SHAPESENSE_VOXELS"), std::invalid_argument);
  EXPECT_THROW(ChannelNetworks::Parse("SHAPESENSE_VOXELS=wan"), std::invalid_argument);
  EXPECT_THROW(ChannelNetworks::Parse("SHAPE[=rig"), std::invalid_argument);
  EXPECT_TRUE(ChannelNetworks::Parse("").empty());
}

TEST(LcmUrlTest, TtlIsReadAndRewrittenKeepingTheOtherOptions) {
  EXPECT_EQ(TtlOf("udpm://239.255.76.67:7667"), 0);
  EXPECT_EQ(TtlOf("udpm://239.255.76.67:7667?recv_buf_size=100&ttl=1"), 1);
  EXPECT_EQ(TtlOf("memq://"), 0);
  EXPECT_EQ(WithTtl("udpm://239.255.76.67:7667?recv_buf_size=100&ttl=1", 0),
            "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=100");
  EXPECT_EQ(GroupAndPort("udpm://239.255.76.67?ttl=1"), "239.255.76.67:7667");
  EXPECT_THROW(SplitUdpm("udpm://239.255.76.67:port"), std::invalid_argument);
}

TEST(ClockOffsetsTest, TheSmallestDelayGivesTheOffsetAndASteppedClockIsFollowed) {
  ClockOffsets offsets(/*window_us=*/1'000'000);
  // beta's clock is 500 ms ahead of ours; transit 100 µs plus up to 5 ms of queueing.
  const int64_t ahead = 500'000;
  for (int i = 0; i < 50; ++i) {
    const int64_t ours = 1'000'000'000 + int64_t{i} * 20'000;
    offsets.Observe("beta", ours + ahead - 100 - int64_t{i % 7} * 700, ours);
  }
  std::vector<HostClockOffset> seen = offsets.Snapshot();
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].host, "beta");
  EXPECT_EQ(seen[0].samples, 50);
  EXPECT_NEAR(static_cast<double>(seen[0].offset_us), ahead, 200.0);
  // beta's clock is stepped back by a second: within two half windows the
  // estimate follows.
  for (int i = 50; i < 150; ++i) {
    const int64_t ours = 1'000'000'000 + int64_t{i} * 20'000;
    offsets.Observe("beta", ours + ahead - 1'000'000 - 100, ours);
  }
  seen = offsets.Snapshot();
  EXPECT_NEAR(static_cast<double>(seen[0].offset_us), ahead - 1'000'000, 200.0);
}

class RigNetworkTest : public testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(nettest::PrivateNetworkError(), ""); }
};

TEST_F(RigNetworkTest, ImagesGoOnTheLocalNetworkAndCompactMessagesOnTheRigNetwork) {
  LcmBus publisher(Options(kRig, kLocal));
  LcmBus rig_listener(Options(kRig));
  LcmBus local_listener(Options(kLocal));
  std::atomic<int> rig_images{0}, rig_shapes{0}, local_images{0}, local_shapes{0};
  rig_listener.Subscribe<image_t>(channels::kImagePattern,
                                  [&](image_t&&, const std::string&, int64_t) { ++rig_images; });
  rig_listener.Subscribe<shape_t>(channels::kShape,
                                  [&](shape_t&&, const std::string&, int64_t) { ++rig_shapes; });
  local_listener.Subscribe<image_t>(
      channels::kImagePattern, [&](image_t&&, const std::string&, int64_t) { ++local_images; });
  local_listener.Subscribe<shape_t>(
      channels::kShape, [&](shape_t&&, const std::string&, int64_t) { ++local_shapes; });
  image_t image{};
  image.camera = "cam0";
  ASSERT_TRUE(publisher.Publish(channels::Image("cam0"), image));
  shape_t shape{};
  ASSERT_TRUE(publisher.Publish(channels::kShape, shape));
  HandleUntil({&rig_listener, &local_listener}, [&] { return rig_shapes + local_images >= 2; });
  EXPECT_EQ(rig_shapes, 1);
  EXPECT_EQ(local_images, 1);
  // Nothing else arrives on the wrong network.
  HandleUntil(
      {&rig_listener, &local_listener}, [] { return false; }, 10);
  EXPECT_EQ(rig_images, 0);
  EXPECT_EQ(local_shapes, 0);
}

TEST_F(RigNetworkTest, ARigNetworkThatLeavesTheHostRefusesWhatOneDatagramCannotCarry) {
  LcmBus bus(Options(kRig, kLocal));
  shape_t big{};
  big.num_points = 4000;  // 4000 * 5 doubles: 160 kB
  big.centerline.assign(4000, {0, 0, 0});
  big.arc_length.assign(4000, 0);
  big.curvature.assign(4000, 0);
  EXPECT_FALSE(bus.Publish(channels::kShape, big));
  EXPECT_EQ(bus.Refused(), 1);
  EXPECT_NE(bus.LastRejection().find("SHAPESENSE_SHAPE"), std::string::npos) << bus.LastRejection();
  // The voxel cloud is documented as tolerant to loss; on the local network
  // any size goes.
  voxel_cloud_t voxels{};
  voxels.num_voxels = 20000;
  voxels.voxels.assign(20000, 0);
  voxels.labels.assign(20000, 0);
  EXPECT_TRUE(bus.Publish(channels::kVoxels, voxels));
  LcmBus local_only(Options(kLocal));
  EXPECT_TRUE(local_only.Publish(channels::kShape, big));
  EXPECT_EQ(bus.Refused() + local_only.Refused(), 1);
}

TEST_F(RigNetworkTest, TwoRigsShareANetworkByTheirPrefixesAndHandlersSeePlainNames) {
  LcmBus rig_a(Options(kRig, kLocal, "RIGA_"));
  LcmBus rig_b(Options(kRig, kLocal, "RIGB_"));
  std::vector<int64_t> heard_a, heard_b;
  rig_a.Subscribe<shape_t>(channels::kShape,
                           [&](shape_t&& shape, const std::string& channel, int64_t) {
                             EXPECT_EQ(channel, channels::kShape);
                             heard_a.push_back(shape.trigger_seq);
                           });
  rig_b.Subscribe<shape_t>(".*", [&](shape_t&& shape, const std::string& channel, int64_t) {
    EXPECT_EQ(channel, channels::kShape);
    heard_b.push_back(shape.trigger_seq);
  });
  shape_t shape{};
  shape.trigger_seq = 1;
  ASSERT_TRUE(rig_a.Publish(channels::kShape, shape));
  shape.trigger_seq = 2;
  ASSERT_TRUE(rig_b.Publish(channels::kShape, shape));
  HandleUntil({&rig_a, &rig_b}, [&] { return heard_a.size() + heard_b.size() >= 2; });
  HandleUntil(
      {&rig_a, &rig_b}, [] { return false; }, 10);
  EXPECT_EQ(heard_a, std::vector<int64_t>{1});
  EXPECT_EQ(heard_b, std::vector<int64_t>{2});
  EXPECT_THROW(LcmBus(Options(kRig, kLocal, "RIG.*")), std::invalid_argument);
}

TEST_F(RigNetworkTest, EveryMessageNamesItsHostAndFeedsTheReceiversClockOffsets) {
  LcmBus alpha(Options(kRig, kLocal, "", "alpha"));
  LcmBus beta(Options(kRig, kLocal, "", "beta"));
  std::vector<std::string> hosts;
  beta.Subscribe<shape_t>(channels::kShape, [&](shape_t&& shape, const std::string&, int64_t) {
    hosts.push_back(shape.header.host);
  });
  for (int i = 0; i < 5; ++i) {
    shape_t shape{};
    shape.header.utime = NowUtime();
    ASSERT_TRUE(alpha.Publish(channels::kShape, shape));
  }
  shape_t named{};
  named.header.host = "gamma";
  named.header.utime = NowUtime() + 300'000;  // gamma's clock: 300 ms ahead
  ASSERT_TRUE(alpha.Publish(channels::kShape, static_cast<const shape_t&>(named)));
  HandleUntil({&alpha, &beta}, [&] { return hosts.size() >= 6; });
  ASSERT_EQ(hosts.size(), 6u);
  EXPECT_EQ(hosts.front(), "alpha");
  EXPECT_EQ(hosts.back(), "gamma");
  const std::vector<HostClockOffset> offsets = beta.clock_offsets().Snapshot();
  ASSERT_EQ(offsets.size(), 2u);
  EXPECT_EQ(offsets[0].host, "alpha");
  EXPECT_EQ(offsets[0].samples, 5);
  EXPECT_NEAR(static_cast<double>(offsets[0].offset_us), 0.0, 20'000.0);
  EXPECT_EQ(offsets[1].host, "gamma");
  EXPECT_NEAR(static_cast<double>(offsets[1].offset_us), 300'000.0, 20'000.0);
  EXPECT_TRUE(alpha.clock_offsets().Snapshot().empty())
      << "its own messages are not another host's";
}

TEST_F(RigNetworkTest, StatusCarriesTheProcessAndEveryPeersClockOffsetAndWarnsPastAMillisecond) {
  LcmBus beta(Options(kRig, kLocal, "", "beta"));
  LcmBus gamma(Options(kRig, kLocal, "", "gamma"));
  LcmBus listener(Options(kRig, kLocal, "", "listener"));
  std::vector<service_status_t> heard;
  listener.Subscribe<service_status_t>(
      channels::Status("carving"),
      [&](service_status_t&& status, const std::string&, int64_t) { heard.push_back(status); });
  ServiceStatus status("carving");
  status.Publish(beta, NowUtime());  // from now on it hears its peers
  for (int i = 0; i < 5; ++i) {
    service_status_t peer{};
    peer.service = "controller";
    peer.header.utime = NowUtime() + 5'000;  // gamma's clock: 5 ms ahead
    ASSERT_TRUE(gamma.Publish(channels::Status("controller"), peer));
  }
  HandleUntil({&beta}, [&] { return beta.clock_offsets().OffsetOf("gamma").has_value(); });
  HandleUntil(
      {&beta}, [] { return false; }, 5);
  status.Publish(beta, NowUtime());
  HandleUntil({&listener}, [&] { return heard.size() >= 2; });
  ASSERT_EQ(heard.size(), 2u);
  const service_status_t& last = heard.back();
  EXPECT_EQ(last.header.host, "beta");
  EXPECT_EQ(last.pid, getpid());
  EXPECT_GT(last.rss_bytes, 0);
  EXPECT_GE(last.uptime_s, 0.0);
  ASSERT_EQ(last.num_clock_offsets, 1) << "gamma's (its own is not another host's)";
  EXPECT_EQ(last.clock_offset_hosts[0], "gamma");
  EXPECT_NEAR(static_cast<double>(last.clock_offsets_us[0]), 5'000.0, 3'000.0);
  EXPECT_NE(last.clock_warning.find("gamma's clock is +"), std::string::npos) << last.clock_warning;
  EXPECT_EQ(last.last_error, last.clock_warning);
  EXPECT_TRUE(heard.front().clock_warning.empty());
}

TEST_F(RigNetworkTest, ImageBusesHangOffTheLocalNetwork) {
  LcmBus main(Options(kRig, kLocal));
  ImageBuses buses(main, 2);
  EXPECT_EQ(buses.ForCamera(1).url(), ImageUrl(kLocal, 1));
  EXPECT_EQ(TtlOf(buses.ForCamera(1).url()), 0);
}

TEST_F(RigNetworkTest, ABusOnANetworkThatLeavesTheHostNeedsTheKeyOrIsToldItIsInsecure) {
  LcmBusOptions bare = Options(kRig, kLocal);
  bare.auth.key_files.clear();
  try {
    LcmBus bus(bare);
    FAIL() << "a bus on a ttl=1 network started without a key";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("SHAPESENSE_KEY_FILES"), std::string::npos)
        << error.what();
  }
  bare.auth.read_only = true;  // a status view acts on nothing
  EXPECT_EQ(LcmBus(bare).AuthSnapshot().mode, "off (read-only)");
  bare.auth.read_only = false;
  bare.auth.insecure = true;
  EXPECT_EQ(LcmBus(bare).AuthSnapshot().mode, "OFF (insecure)");
  EXPECT_EQ(LcmBus(Options(kRig, kLocal)).AuthSnapshot().mode, "on (key 1)");
}

}  // namespace
}  // namespace shapesense
