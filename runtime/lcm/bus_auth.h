#pragma once

// Message authentication on an LcmBus (docs/security.md). The channels that
// move the robot or feed the controller are signed by every publisher that
// holds the rig key and verified by every receiver that holds it: an
// HMAC-SHA256 (libs/security) over the message as it travels, bound to its
// channel, with the signer's key id, name and counter in the message's
// header (auth_t). Receivers act only on messages that are authentic and
// fresh; the others are counted by reason for the status.
#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "libs/security/message_auth.h"
#include "runtime/lcm/wire_check.h"
#include "shapesense/estop_t.hpp"
#include "shapesense/header_t.hpp"

namespace shapesense {

// The channels whose messages are signed and verified: targets, the e-stop,
// tendon and plant commands, the plant's actuators and the sensed shapes
// (which carry the configuration q). `channel` without the rig prefix.
bool IsSignedChannel(const std::string& channel);

// Whether a message on a signed channel is acted on without a valid
// signature: only engaging the e-stop, because a stop that is refused for
// want of a key is worse than a stop that nobody asked for (security.md).
template <class Message>
bool AcceptedUnsigned(const Message& /*message*/) {
  return false;
}
inline bool AcceptedUnsigned(const estop_t& estop) { return estop.engaged; }

// Where a message's MAC lies in its encoding: header_t is the first field of
// every type, auth_t the last of header_t and its mac the last of auth_t.
template <class Message>
size_t MacOffset(const Message& message) {
  constexpr size_t kFingerprintBytes = 8;
  return kFingerprintBytes + static_cast<size_t>(message.header._getEncodedSizeNoHash()) -
         kMacBytes;
}

// The tag a receiver verifies, as the message carries it.
AuthTag TagOf(const auth_t& auth);

// `message` encoded with `signer`'s next tag (its counter raised to
// `counter_floor`) and the MAC for `wire_channel` in place.
template <class Message>
std::vector<uint8_t> EncodeSigned(Message message, MessageSigner& signer,
                                  const std::string& wire_channel, uint64_t counter_floor) {
  const AuthTag tag = signer.Next(counter_floor);
  auth_t& auth = message.header.auth;
  auth.key_id = static_cast<int32_t>(tag.key_id);
  auth.sender = tag.sender;
  auth.counter = static_cast<int64_t>(tag.counter);
  std::fill(std::begin(auth.mac), std::end(auth.mac), 0);
  std::vector<uint8_t> bytes = EncodeMessage(message);
  const size_t mac_offset = MacOffset(message);
  const Mac mac = signer.Sign(wire_channel, tag, bytes, mac_offset);
  std::copy(mac.begin(), mac.end(), bytes.begin() + static_cast<std::ptrdiff_t>(mac_offset));
  return bytes;
}

// What a bus's authentication did, for the status.
struct AuthCounts {
  std::string mode;  // "on (keys 3, 4)", "off (host-local)", "OFF (insecure)"
  int64_t accepted = 0;
  int64_t estops_accepted_unsigned = 0;
  std::map<std::string, int64_t> rejections;  // by reason (AuthRejectionName)
};

// How a program authenticates: from SHAPESENSE_KEY_FILES and
// SHAPESENSE_INSECURE (what `shapesense rig units` and the demo set).
struct AuthOptions {
  // One or two key files (the second: the key being rotated in, which
  // signs); empty: no authentication.
  std::vector<std::filesystem::path> key_files;
  // Runs without keys on a rig network that leaves the host (loudly).
  bool insecure = false;
  // A bus that only watches (a status view) and publishes nothing signed
  // needs no key; with keys it verifies as any other.
  bool read_only = false;
  // The signer's name; empty: "host/program".
  std::string sender;
  // Which counters may open a sender's window (FirstContactRule; the
  // receiver's start is the bus's).
  FirstContactRule first_contact;

  // Throws std::invalid_argument naming the variable on a bad value
  // (read with the rest of LcmBusOptions::FromEnvironment).
  static AuthOptions FromEnvironment();
};

// SHAPESENSE_KEY_FILES' value: the files joined by ':', and back.
std::string FormatKeyFiles(const std::vector<std::filesystem::path>& files);
std::vector<std::filesystem::path> ParseKeyFiles(const std::string& value);

// The signing and verifying state of one bus, safe from any thread.
class BusAuth {
 public:
  // Off when `keys` is empty.
  BusAuth(std::optional<KeyRing> keys, std::string sender, FirstContactRule first_contact,
          std::string off_mode);

  bool on() const { return signer_.has_value(); }

  // Signs a copy of `message` for `wire_channel` (the channel with the rig
  // prefix) and hands its bytes to `send` under one lock, so that each
  // channel's messages leave in the order of their counters.
  template <class Message, class Send>
  bool SignAndSend(const std::string& wire_channel, const Message& message, Send send) {
    const std::lock_guard lock(sign_mutex_);
    const std::vector<uint8_t> bytes =
        EncodeSigned(message, *signer_, wire_channel, CounterFloor());
    return send(std::span<const uint8_t>(bytes));
  }

  // "" when `message`, decoded from `bytes` as received on a signed
  // channel, may be acted on; otherwise why not (counted). Everything when
  // off. `now_utime`: this host's clock. `subscription`: which of the bus's
  // subscriptions asks: LCM hands one datagram to every subscription that
  // matches it, and each keeps its own replay windows, so that the second
  // is no replay of the first.
  template <class Message>
  std::string Admit(int subscription, const std::string& wire_channel,
                    std::span<const uint8_t> bytes, const Message& message, int64_t now_utime) {
    if (!on()) return {};
    const auth_t& auth = message.header.auth;
    if (!AcceptedUnsigned(message)) {
      return Verify(subscription, wire_channel, bytes, auth, MacOffset(message), now_utime);
    }
    // Verified when signed (so that the window and the counts see it),
    // acted on either way.
    const bool authentic =
        !auth.sender.empty() &&
        Verify(subscription, wire_channel, bytes, auth, MacOffset(message), now_utime).empty();
    if (!authentic) CountUnsignedEstop();
    return {};
  }

  AuthCounts Counts() const;

 private:
  std::string Verify(int subscription, const std::string& wire_channel,
                     std::span<const uint8_t> bytes, const auth_t& auth, size_t mac_offset,
                     int64_t now_utime);
  void CountUnsignedEstop();
  static uint64_t CounterFloor();

  std::optional<MessageSigner> signer_;
  std::optional<KeyRing> keys_;
  FirstContactRule first_contact_;
  std::map<int, MessageVerifier> verifiers_;  // by subscription
  std::string off_mode_;
  std::mutex sign_mutex_;
  mutable std::mutex verify_mutex_;
  int64_t estops_accepted_unsigned_ = 0;
};

// The sender name of this process's `index`-th bus: "host/program", then
// "#index" after the first (each bus keeps its own counter).
std::string DefaultSender(const std::string& host, int index);

}  // namespace shapesense
