#pragma once

// Signing and verifying messages that move the robot (docs/security.md):
// an HMAC-SHA256 over the message's encoded bytes, as they travel, with the
// MAC's own bytes taken as zeros, bound to the channel. The bytes cover the
// key id, the sender and its counter (they are in the message), so none can
// be changed. Freshness is the sender's counter in a replay window, never a
// clock. A verifier checks the MAC before the window, so that forgeries
// cannot move it, and counts every rejection by its reason.
#include <algorithm>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "libs/security/auth_key.h"
#include "libs/security/hmac.h"
#include "libs/security/replay_window.h"

namespace shapesense {

// Who signed a message, with which key, and its place in the sender's sequence.
struct AuthTag {
  uint32_t key_id = 0;
  std::string sender;  // empty: unsigned
  uint64_t counter = 0;
};

// The MAC of `encoded` (a whole LCM message, fingerprint first) whose MAC
// field is the kMacBytes at `mac_offset`; throws std::out_of_range when the
// field is not inside the message.
Mac MessageMac(const AuthKey& key, std::string_view channel, std::span<const uint8_t> encoded,
               size_t mac_offset);

enum class AuthRejection { kUnsigned, kUnknownKey, kBadMac, kReplayed, kTooOld, kMalformed };
// "unsigned", "unknown_key", "bad_mac", "replayed", "too_old", "malformed"
const char* AuthRejectionName(AuthRejection rejection);

// Which counter may open a sender's window. Senders count from their
// clock in µs (auth_t), never below it, so a message sent after the
// receiver started carries a counter above the receiver's start, give or
// take the offset between the two clocks; a recording made before then
// (an earlier run, a log) does not, and cannot open a window (as MAVLink 2's
// signing bounds a new stream's timestamp). This is the only place a clock
// enters, with a tolerance far beyond a rig's offsets; afterwards the
// counters alone decide.
struct FirstContactRule {
  int64_t receiver_start_utime = 0;  // 0: any first counter
  int64_t max_age_us = 60'000'000;   // and never older than this
  int64_t clock_tolerance_us = 5'000'000;

  bool Admits(uint64_t counter, int64_t now_utime) const;
};

// Replay windows are kept per sender and channel: a sender signs each
// channel's messages in the order it sends them, whatever its threads do
// across channels, and the MAC binds the channel, so no message counts on
// another channel's window.
class MessageVerifier {
 public:
  explicit MessageVerifier(KeyRing keys, FirstContactRule first_contact = {})
      : keys_(std::move(keys)), first_contact_(first_contact) {}

  // nullopt when authentic and fresh (its counter is then recorded);
  // otherwise why not, counted. `now_utime`: the receiver's clock, for a
  // first contact.
  std::optional<AuthRejection> Verify(std::string_view channel, const AuthTag& tag,
                                      std::span<const uint8_t> encoded, size_t mac_offset,
                                      int64_t now_utime = 0);
  // Counts a rejection found before verifying (a message that does not decode).
  void Count(AuthRejection rejection) { ++rejections_[AuthRejectionName(rejection)]; }
  // Every rejection so far, by reason name.
  const std::map<std::string, int64_t>& rejections() const { return rejections_; }
  int64_t accepted() const { return accepted_; }

 private:
  std::optional<AuthRejection> Reject(AuthRejection rejection);

  KeyRing keys_;
  FirstContactRule first_contact_;
  std::map<std::pair<std::string, std::string>, ReplayWindow> windows_;  // by sender, channel
  std::map<std::string, int64_t> rejections_;
  int64_t accepted_ = 0;
};

class MessageSigner {
 public:
  // `first_counter`: above every counter this sender used before (a
  // restarted sender starts from its start time in µs, see security.md).
  MessageSigner(KeyRing keys, std::string sender, uint64_t first_counter)
      : keys_(std::move(keys)), sender_(std::move(sender)), next_(first_counter) {}

  // The tag for the next message: the newest key, this sender, its counter,
  // raised to `floor` when that is higher (the clock in µs: a counter that
  // stays near the clock lets a receiver that starts later tell a live
  // sender from a recording, see MessageVerifier).
  AuthTag Next(uint64_t floor = 0) {
    next_ = std::max(next_, floor);
    return {keys_.signing().id, sender_, next_++};
  }
  const KeyRing& keys() const { return keys_; }
  // The MAC of a message carrying `tag` (key looked up by the tag's id).
  Mac Sign(std::string_view channel, const AuthTag& tag, std::span<const uint8_t> encoded,
           size_t mac_offset) const;

 private:
  KeyRing keys_;
  std::string sender_;
  uint64_t next_;
};

}  // namespace shapesense
