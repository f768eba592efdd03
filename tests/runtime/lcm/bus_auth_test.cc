// Message authentication on the bus (docs/security.md): every type that
// carries a MAC rejects every single flipped bit; over real UDP multicast,
// signed messages reach their handlers and unsigned, forged, unknown-key,
// replayed and stale ones never do, each counted by its reason in the
// status; engaging the e-stop needs no signature, releasing it does; hosts
// whose clocks are 0.5 s apart authenticate; a rotation keeps two keys
// valid; a key file that others can read stops the program.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <atomic>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "runtime/host_clock.h"
#include "runtime/lcm/bus_auth.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/lcm/service_status.h"
#include "runtime/lcm/wire_check.h"
#include "runtime/security/key_file.h"
#include "shapesense/configuration_target_t.hpp"
#include "shapesense/estop_t.hpp"
#include "shapesense/shape_t.hpp"
#include "shapesense/tendon_command_t.hpp"
#include "shapesense/tendon_state_t.hpp"
#include "tests/runtime/lcm/temporary_key_file.h"
#include "tests/support/network_test.h"

namespace shapesense {
namespace {

constexpr const char* kUrl = "udpm://239.255.78.9:7861?ttl=0";

// The key files of the tests: one rig key, and keys a stranger might hold.
AuthKey FixedKey(uint32_t id, uint8_t fill) {
  AuthKey key;
  key.id = id;
  key.secret.fill(fill);
  return key;
}

KeyRing Ring(std::initializer_list<AuthKey> keys) { return KeyRing(std::vector<AuthKey>(keys)); }

configuration_target_t Target() {
  configuration_target_t target{};
  target.kind = configuration_target_t::KIND_CONFIGURATION;
  target.q[0] = 0.004;
  target.q[3] = 1e-3;
  target.duration_s = 1.5;
  target.source = "test";
  return target;
}

estop_t Estop(bool engaged) {
  estop_t estop{};
  estop.engaged = engaged;
  estop.reason = engaged ? "button" : "operator release";
  estop.source = "console";
  return estop;
}

tendon_command_t Command() {
  tendon_command_t command{};
  command.num_tendons = 2;
  command.displacement_mm = {1.25, -0.5};
  command.source_trigger_seq = 41;
  command.mode = tendon_command_t::MODE_CLOSED_LOOP;
  return command;
}

tendon_state_t State() {
  tendon_state_t state{};
  state.num_tendons = 2;
  state.displacement_mm = {1.0, 0.5};
  state.tension_n = {2.0, 3.0};
  state.fault = {0, 0};
  return state;
}

shape_t Shape() {
  shape_t shape{};
  shape.trigger_seq = 17;
  shape.valid = true;
  shape.num_points = 3;
  shape.centerline = {{0, 0, 0}, {0, 0, 10}, {1, 0, 20}};
  shape.arc_length = {0, 10, 20.05};
  shape.curvature = {0.001, 0.002, 0.003};
  shape.tip[2] = 20;
  shape.length = 20.05;
  shape.has_configuration = true;
  shape.q[0] = 0.004;
  return shape;
}

// Flips each bit of `bytes` in turn and asks a fresh receiver with the same
// key whether it would act on the result; returns the bits it accepted.
template <class Message>
std::vector<size_t> AcceptedFlips(const std::vector<uint8_t>& bytes, const std::string& channel) {
  std::vector<size_t> accepted;
  const int64_t now = HostUtime();
  for (size_t bit = 0; bit < bytes.size() * 8; ++bit) {
    std::vector<uint8_t> flipped = bytes;
    flipped[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
    Message message;
    if (!DecodeMessage(flipped.data(), flipped.size(), &message).empty()) continue;  // malformed
    BusAuth receiver(Ring({FixedKey(1, 0x5a)}), "receiver", FirstContactRule{}, "");
    if (receiver.Admit(0, channel, flipped, message, now).empty()) accepted.push_back(bit);
  }
  return accepted;
}

template <class Message>
std::vector<uint8_t> Signed(const Message& message, const std::string& channel) {
  MessageSigner signer(Ring({FixedKey(1, 0x5a)}), "camera/shapesense-shape", 0);
  return EncodeSigned(message, signer, channel, static_cast<uint64_t>(HostUtime()));
}

template <class Message>
void ExpectEveryFlipRejected(const Message& message, const std::string& channel) {
  const std::vector<uint8_t> bytes = Signed(message, channel);
  Message decoded;
  ASSERT_EQ(DecodeMessage(bytes.data(), bytes.size(), &decoded), "");
  BusAuth receiver(Ring({FixedKey(1, 0x5a)}), "receiver", FirstContactRule{}, "");
  ASSERT_EQ(receiver.Admit(0, channel, bytes, decoded, HostUtime()), "") << "the message itself";
  EXPECT_EQ(AcceptedFlips<Message>(bytes, channel), std::vector<size_t>{})
      << Message::getTypeName() << " on " << channel << ", " << bytes.size() << " bytes";
}

TEST(BusAuthTest, EverySignedTypeRejectsEverySingleFlippedBit) {
  ExpectEveryFlipRejected(Target(), channels::kTarget);
  ExpectEveryFlipRejected(Command(), channels::kPlantCommand);
  ExpectEveryFlipRejected(Command(), channels::kTendonCommand);
  ExpectEveryFlipRejected(State(), channels::kPlantState);
  ExpectEveryFlipRejected(Shape(), channels::kShape);
}

TEST(BusAuthTest, AFlipThatTurnsAReleaseIntoAnEngageStopsTheRobotAndNothingElsePasses) {
  // A release with any bit flipped is refused, except where the flip makes
  // it an engaged e-stop, which is acted on unsigned by design: the only
  // flips accepted are those of `engaged` (any non-zero byte is true).
  const estop_t release = Estop(false);
  const std::vector<uint8_t> bytes = Signed(release, channels::kEstop);
  const std::vector<size_t> accepted = AcceptedFlips<estop_t>(bytes, channels::kEstop);
  ASSERT_EQ(accepted.size(), 8u);
  const size_t engaged_byte = accepted.front() / 8;
  for (const size_t bit : accepted) EXPECT_EQ(bit / 8, engaged_byte);
  estop_t flipped;
  std::vector<uint8_t> copy = bytes;
  copy[engaged_byte] ^= 1;
  ASSERT_EQ(DecodeMessage(copy.data(), copy.size(), &flipped), "");
  EXPECT_TRUE(flipped.engaged);
}

// A recognisable MAC, a host and a sender of their own lengths: the MAC's
// bytes are where MacOffset says.
template <class Message>
void ExpectMacAtItsOffset(Message message) {
  message.header.host = "camera";
  message.header.auth.sender = "camera/shapesense-shape";
  for (size_t i = 0; i < kMacBytes; ++i) {
    message.header.auth.mac[i] = static_cast<uint8_t>(0xa0 + i);
  }
  const std::vector<uint8_t> bytes = EncodeMessage(message);
  const size_t offset = MacOffset(message);
  ASSERT_LE(offset + kMacBytes, bytes.size()) << Message::getTypeName();
  for (size_t i = 0; i < kMacBytes; ++i) {
    EXPECT_EQ(bytes[offset + i], 0xa0 + i) << Message::getTypeName() << " byte " << i;
  }
}

TEST(BusAuthTest, TheMacSitsAtTheEndOfTheHeaderInEveryType) {
  ExpectMacAtItsOffset(Target());
  ExpectMacAtItsOffset(Estop(false));
  ExpectMacAtItsOffset(Command());
  ExpectMacAtItsOffset(State());
  ExpectMacAtItsOffset(Shape());
}

// Several buses on one network, and a raw LCM for what no bus would send.
class BusAuthNetworkTest : public testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(nettest::PrivateNetworkError(), ""); }

  static LcmBusOptions With(const std::vector<std::filesystem::path>& keys,
                            const std::string& sender) {
    LcmBusOptions options;
    options.url = kUrl;
    options.auth.key_files = keys;
    options.auth.sender = sender;
    return options;
  }
  template <class Done>
  static void HandleUntil(std::initializer_list<LcmBus*> buses, Done done, int rounds = 200) {
    for (int i = 0; i < rounds && !done(); ++i) {
      for (LcmBus* bus : buses) bus->Handle(5);
    }
  }
  // Handles what is in flight: up to `rounds` quiet rounds of 5 ms.
  static void Drain(std::initializer_list<LcmBus*> buses, int rounds = 20) {
    HandleUntil(
        buses, [] { return false; }, rounds);
  }

  AuthKey rig_key_ = FixedKey(7, 0x3c);
  test_keys::TemporaryKeyFile rig_{7, &rig_key_};
};

int64_t Rejections(const LcmBus& bus, const std::string& reason) {
  const AuthCounts counts = bus.AuthSnapshot();
  const auto found = counts.rejections.find(reason);
  return found == counts.rejections.end() ? 0 : found->second;
}

TEST_F(BusAuthNetworkTest, OnlyAuthenticFreshMessagesReachAHandlerAndEveryOtherIsCounted) {
  LcmBus controller(With({rig_.path()}, "control/controller"));
  LcmBus operator_console(With({rig_.path()}, "operator/console"));
  const AuthKey other_secret = FixedKey(7, 0x77);
  const test_keys::TemporaryKeyFile forger_key(7, &other_secret);
  LcmBus forger(With({forger_key.path()}, "operator/console"));
  const test_keys::TemporaryKeyFile stranger_key(99);
  LcmBus stranger(With({stranger_key.path()}, "laptop/stranger"));
  LcmBus unsigned_sender(With({}, "laptop/plain"));  // ttl=0 without keys: signs nothing
  EXPECT_EQ(unsigned_sender.AuthSnapshot().mode, "off (host-local)");
  EXPECT_EQ(controller.AuthSnapshot().mode, "on (key 7)");

  std::vector<double> heard;
  controller.Subscribe<configuration_target_t>(
      channels::kTarget, [&](configuration_target_t&& target, const std::string&, int64_t) {
        heard.push_back(target.duration_s);
      });
  // Every raw datagram on the channel, kept to be replayed.
  lcm::LCM tap(kUrl);
  std::vector<std::vector<uint8_t>> recorded;
  tap.subscribeFunction(
      channels::kTarget,
      +[](const lcm::ReceiveBuffer* buffer, const std::string&,
          std::vector<std::vector<uint8_t>>* out) {
        const auto* data = static_cast<const uint8_t*>(buffer->data);
        out->emplace_back(data, data + buffer->data_size);
      },
      &recorded);

  configuration_target_t target = Target();
  target.duration_s = 1.0;
  ASSERT_TRUE(operator_console.Publish(channels::kTarget, target));
  HandleUntil({&controller}, [&] { return !heard.empty(); });
  ASSERT_EQ(heard, std::vector<double>{1.0});
  for (int i = 0; i < 50 && recorded.empty(); ++i) tap.handleTimeout(10);
  ASSERT_EQ(recorded.size(), 1u);

  target.duration_s = 2.0;  // each of these would move the robot
  ASSERT_TRUE(unsigned_sender.Publish(channels::kTarget, target));
  ASSERT_TRUE(forger.Publish(channels::kTarget, target));
  ASSERT_TRUE(stranger.Publish(channels::kTarget, target));
  tap.publish(channels::kTarget, recorded[0].data(), static_cast<unsigned>(recorded[0].size()));
  Drain({&controller});
  EXPECT_EQ(heard, std::vector<double>{1.0});
  EXPECT_EQ(Rejections(controller, "unsigned"), 1);
  EXPECT_EQ(Rejections(controller, "bad_mac"), 1);
  EXPECT_EQ(Rejections(controller, "unknown_key"), 1);
  EXPECT_EQ(Rejections(controller, "replayed"), 1);
  EXPECT_EQ(controller.AuthSnapshot().accepted, 1);
  EXPECT_EQ(controller.Rejected(), 4);
  EXPECT_NE(controller.LastRejection().find("not authentic (replayed)"), std::string::npos)
      << controller.LastRejection();

  // The status says what was rejected and why.
  std::vector<service_status_t> statuses;
  controller.Subscribe<service_status_t>(
      channels::Status("controller"),
      [&](service_status_t&& status, const std::string&, int64_t) { statuses.push_back(status); });
  ServiceStatus status("controller");
  status.Publish(controller, HostUtime());
  HandleUntil({&controller}, [&] { return !statuses.empty(); });
  ASSERT_EQ(statuses.size(), 1u);
  EXPECT_EQ(statuses[0].auth, "on (key 7)");
  EXPECT_EQ(statuses[0].auth_accepted, 1);
  EXPECT_EQ(statuses[0].auth_rejection_reasons,
            (std::vector<std::string>{"bad_mac", "replayed", "unknown_key", "unsigned"}));
  EXPECT_EQ(statuses[0].auth_rejections, (std::vector<int64_t>{1, 1, 1, 1}));
}

TEST_F(BusAuthNetworkTest, EngagingTheEstopNeedsNoSignatureReleasingItDoes) {
  LcmBus controller(With({rig_.path()}, "control/controller"));
  LcmBus operator_console(With({rig_.path()}, "operator/console"));
  LcmBus button(With({}, "bench/button"));
  std::vector<bool> heard;
  controller.Subscribe<estop_t>(channels::kEstop, [&](estop_t&& estop, const std::string&,
                                                      int64_t) { heard.push_back(estop.engaged); });
  ASSERT_TRUE(button.Publish(channels::kEstop, Estop(true)));
  HandleUntil({&controller}, [&] { return heard.size() == 1; });
  ASSERT_TRUE(button.Publish(channels::kEstop, Estop(false)));  // refused
  Drain({&controller});
  ASSERT_TRUE(operator_console.Publish(channels::kEstop, Estop(false)));
  HandleUntil({&controller}, [&] { return heard.size() == 2; });
  EXPECT_EQ(heard, (std::vector<bool>{true, false}));
  EXPECT_EQ(controller.AuthSnapshot().estops_accepted_unsigned, 1);
  EXPECT_EQ(Rejections(controller, "unsigned"), 1);
}

// A key holder's message signed out of turn: the rig key, but a counter of
// our choosing, published raw.
void PublishWithCounter(lcm::LCM& raw, const AuthKey& key, const std::string& sender,
                        int64_t counter, double duration_s) {
  MessageSigner signer(Ring({key}), sender, static_cast<uint64_t>(counter));
  configuration_target_t target = Target();
  target.duration_s = duration_s;
  const std::vector<uint8_t> bytes = EncodeSigned(target, signer, channels::kTarget, 0);
  raw.publish(channels::kTarget, bytes.data(), static_cast<unsigned>(bytes.size()));
}

TEST_F(BusAuthNetworkTest, CountersNotClocksTellFreshFromStaleAndHalfASecondApartIsFine) {
  LcmBus controller(With({rig_.path()}, "control/controller"));
  std::vector<double> heard;
  controller.Subscribe<configuration_target_t>(
      channels::kTarget, [&](configuration_target_t&& target, const std::string&, int64_t) {
        heard.push_back(target.duration_s);
      });
  lcm::LCM raw(kUrl);
  const int64_t now = HostUtime();
  // A host whose clock is 0.5 s behind ours, another 0.5 s ahead: both heard.
  PublishWithCounter(raw, rig_key_, "behind/console", now - 500'000, 1.0);
  PublishWithCounter(raw, rig_key_, "ahead/console", now + 500'000, 2.0);
  HandleUntil({&controller}, [&] { return heard.size() == 2; });
  // The one ahead goes on counting from its own counter: a lower one is stale.
  PublishWithCounter(raw, rig_key_, "ahead/console", now + 500'000 + 1, 3.0);
  PublishWithCounter(raw, rig_key_, "ahead/console", now + 500'000 - 1000, 4.0);
  // A recording of a run two minutes ago opens no window.
  PublishWithCounter(raw, rig_key_, "old/console", now - 120'000'000, 5.0);
  Drain({&controller});
  EXPECT_EQ(heard, (std::vector<double>{1.0, 2.0, 3.0}));
  EXPECT_EQ(Rejections(controller, "too_old"), 2);
}

TEST_F(BusAuthNetworkTest, ARotationKeepsTheOldKeyValidUntilItIsDropped) {
  const AuthKey next = FixedKey(8, 0x44);
  const test_keys::TemporaryKeyFile next_key(8, &next);
  LcmBus receiver(With({rig_.path(), next_key.path()}, "control/controller"));
  LcmBus old_sender(With({rig_.path()}, "camera/old"));
  LcmBus new_sender(With({rig_.path(), next_key.path()}, "camera/new"));
  LcmBus receiver_after(With({next_key.path()}, "control/after"));
  EXPECT_EQ(receiver.AuthSnapshot().mode, "on (keys 7, 8)");
  int heard = 0;
  int heard_after = 0;
  receiver.Subscribe<tendon_command_t>(
      channels::kPlantCommand, [&](tendon_command_t&&, const std::string&, int64_t) { ++heard; });
  receiver_after.Subscribe<tendon_command_t>(
      channels::kPlantCommand,
      [&](tendon_command_t&&, const std::string&, int64_t) { ++heard_after; });
  ASSERT_TRUE(old_sender.Publish(channels::kPlantCommand, Command()));
  ASSERT_TRUE(new_sender.Publish(channels::kPlantCommand, Command()));  // signed with key 8
  HandleUntil({&receiver, &receiver_after}, [&] { return heard == 2 && heard_after == 1; });
  Drain({&receiver, &receiver_after});
  EXPECT_EQ(heard, 2);
  EXPECT_EQ(heard_after, 1);
  EXPECT_EQ(Rejections(receiver_after, "unknown_key"), 1);
}

TEST_F(BusAuthNetworkTest, AKeyFileOthersCanReadStopsTheProgramWithoutShowingTheKey) {
  ASSERT_EQ(::chmod(rig_.path().c_str(), 0644), 0);
  try {
    LcmBus bus(With({rig_.path()}, "control/controller"));
    FAIL() << "a key file of mode 0644 was accepted";
  } catch (const std::exception& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(rig_.path().string()), std::string::npos) << message;
    EXPECT_EQ(message.find("3c3c3c"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace shapesense
