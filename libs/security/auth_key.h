#pragma once

// The rig's message keys (docs/security.md): 256-bit secrets with ids. A
// ring holds at most two at once, so that a rotation keeps the old key valid
// while every host takes the new one; messages are signed with the newest.
// A secret never appears in a message of this code: errors name the file
// and the key, never the value.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "libs/security/hmac.h"

namespace shapesense {

struct AuthKey {
  uint32_t id = 0;
  std::array<uint8_t, kAuthKeyBytes> secret{};
};

// A key file's text:
//   # shapesense message key (docs/security.md) ...
//   key_id: 3
//   secret: <64 hex digits>
// Throws InputError naming `source` and what is wrong (never the secret).
AuthKey ParseKeyText(const std::string& text, const std::string& source);
std::string FormatKeyText(const AuthKey& key);

class KeyRing {
 public:
  static constexpr size_t kMaxKeys = 2;

  // Keys in order of age, the newest last; throws InputError when empty,
  // more than kMaxKeys, or two share an id.
  explicit KeyRing(std::vector<AuthKey> keys);

  const AuthKey& signing() const { return keys_.back(); }
  // The key of `id`, nullptr when the ring has none.
  const AuthKey* Find(uint32_t id) const;
  std::vector<uint32_t> ids() const;

 private:
  std::vector<AuthKey> keys_;
};

}  // namespace shapesense
