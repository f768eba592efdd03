#pragma once

// Keys for the tests: a secret of `fill` bytes, its first byte the id.
#include <cstdint>

#include "libs/security/auth_key.h"

namespace shapesense::testing {

inline AuthKey TestKey(uint32_t id, uint8_t fill) {
  AuthKey key;
  key.id = id;
  key.secret.fill(fill);
  key.secret[0] = static_cast<uint8_t>(id);
  return key;
}

}  // namespace shapesense::testing
