#pragma once

// Signing and verifying messages that move the robot (docs/security.md):
// an HMAC-SHA256 over the message's encoded bytes, as they travel, with the
// MAC's own bytes taken as zeros, bound to the channel. The bytes cover the
// key id, the sender and its counter (they are in the message), so none can
// be changed. Freshness is the sender's counter in a replay window, never a
// clock. A verifier checks the MAC before the window, so that forgeries
// cannot move it, and counts every rejection by its reason.
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>

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

class MessageVerifier {
 public:
  explicit MessageVerifier(KeyRing keys) : keys_(std::move(keys)) {}

  // nullopt when authentic and fresh (its counter is then recorded);
  // otherwise why not, counted.
  std::optional<AuthRejection> Verify(std::string_view channel, const AuthTag& tag,
                                      std::span<const uint8_t> encoded, size_t mac_offset);
  // Counts a rejection found before verifying (a message that does not decode).
  void Count(AuthRejection rejection) { ++rejections_[AuthRejectionName(rejection)]; }
  // Every rejection so far, by reason name.
  const std::map<std::string, int64_t>& rejections() const { return rejections_; }
  int64_t accepted() const { return accepted_; }

 private:
  std::optional<AuthRejection> Reject(AuthRejection rejection);

  KeyRing keys_;
  std::map<std::string, ReplayWindow> windows_;  // by sender
  std::map<std::string, int64_t> rejections_;
  int64_t accepted_ = 0;
};

class MessageSigner {
 public:
  // `first_counter`: above every counter this sender used before (a
  // restarted sender starts from its start time in µs, see security.md).
  MessageSigner(KeyRing keys, std::string sender, uint64_t first_counter)
      : keys_(std::move(keys)), sender_(std::move(sender)), next_(first_counter) {}

  // The tag for the next message: the newest key, this sender, its counter.
  AuthTag Next() { return {keys_.signing().id, sender_, next_++}; }
  // The MAC of a message carrying `tag` (key looked up by the tag's id).
  Mac Sign(std::string_view channel, const AuthTag& tag, std::span<const uint8_t> encoded,
           size_t mac_offset) const;

 private:
  KeyRing keys_;
  std::string sender_;
  uint64_t next_;
};

}  // namespace shapesense
