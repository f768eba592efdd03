#include "libs/security/message_auth.h"

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace shapesense {
namespace {

// Separates this use of the key from any other the rig might make of it.
constexpr std::string_view kDomain = "shapesense message v1";

std::span<const uint8_t> Bytes(std::string_view text) {
  return {reinterpret_cast<const uint8_t*>(text.data()), text.size()};
}

}  // namespace

Mac MessageMac(const AuthKey& key, std::string_view channel, std::span<const uint8_t> encoded,
               size_t mac_offset) {
  if (mac_offset > encoded.size() || encoded.size() - mac_offset < kMacBytes) {
    throw std::out_of_range("MessageMac: the MAC field is not inside the message");
  }
  static constexpr std::array<uint8_t, kMacBytes> kZeros{};
  // The channel's length first, so that no channel and message can pass for
  // another pair.
  const uint32_t channel_size = static_cast<uint32_t>(channel.size());
  const std::array<uint8_t, 4> size_bytes = {
      static_cast<uint8_t>(channel_size >> 24), static_cast<uint8_t>(channel_size >> 16),
      static_cast<uint8_t>(channel_size >> 8), static_cast<uint8_t>(channel_size)};
  const std::vector<std::span<const uint8_t>> parts = {
      Bytes(kDomain), size_bytes,
      Bytes(channel), encoded.first(mac_offset),
      kZeros,         encoded.subspan(mac_offset + kMacBytes)};
  return HmacSha256(key.secret, parts);
}

bool FirstContactRule::Admits(uint64_t counter, int64_t now_utime) const {
  if (receiver_start_utime == 0) return true;
  const int64_t floor = std::max(receiver_start_utime, now_utime - max_age_us) - clock_tolerance_us;
  return counter >= static_cast<uint64_t>(std::max<int64_t>(floor, 0));
}

const char* AuthRejectionName(AuthRejection rejection) {
  switch (rejection) {
    case AuthRejection::kUnsigned:
      return "unsigned";
    case AuthRejection::kUnknownKey:
      return "unknown_key";
    case AuthRejection::kBadMac:
      return "bad_mac";
    case AuthRejection::kReplayed:
      return "replayed";
    case AuthRejection::kTooOld:
      return "too_old";
    case AuthRejection::kMalformed:
      return "malformed";
  }
  return "?";
}

std::optional<AuthRejection> MessageVerifier::Verify(std::string_view channel, const AuthTag& tag,
                                                     std::span<const uint8_t> encoded,
                                                     size_t mac_offset, int64_t now_utime) {
  if (tag.sender.empty()) return Reject(AuthRejection::kUnsigned);
  const AuthKey* key = keys_.Find(tag.key_id);
  if (key == nullptr) return Reject(AuthRejection::kUnknownKey);
  if (mac_offset > encoded.size() || encoded.size() - mac_offset < kMacBytes) {
    return Reject(AuthRejection::kMalformed);
  }
  const Mac expected = MessageMac(*key, channel, encoded, mac_offset);
  if (!MacsEqual(expected, encoded.subspan(mac_offset, kMacBytes))) {
    return Reject(AuthRejection::kBadMac);
  }
  const auto window_key = std::make_pair(tag.sender, std::string(channel));
  const auto window = windows_.find(window_key);
  if (window == windows_.end() && !first_contact_.Admits(tag.counter, now_utime)) {
    return Reject(AuthRejection::kTooOld);
  }
  ReplayWindow& replay = window != windows_.end() ? window->second : windows_[window_key];
  switch (replay.Accept(tag.counter)) {
    case ReplayWindow::Verdict::kFresh:
      ++accepted_;
      return std::nullopt;
    case ReplayWindow::Verdict::kReplayed:
      return Reject(AuthRejection::kReplayed);
    case ReplayWindow::Verdict::kTooOld:
      return Reject(AuthRejection::kTooOld);
  }
  return Reject(AuthRejection::kMalformed);
}

std::optional<AuthRejection> MessageVerifier::Reject(AuthRejection rejection) {
  Count(rejection);
  return rejection;
}

Mac MessageSigner::Sign(std::string_view channel, const AuthTag& tag,
                        std::span<const uint8_t> encoded, size_t mac_offset) const {
  const AuthKey* key = keys_.Find(tag.key_id);
  if (key == nullptr)
    throw std::invalid_argument("MessageSigner: no key " + std::to_string(tag.key_id));
  return MessageMac(*key, channel, encoded, mac_offset);
}

}  // namespace shapesense
