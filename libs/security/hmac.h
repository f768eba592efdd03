#pragma once

// HMAC-SHA256 from OpenSSL's libcrypto (no cryptography of our own), and a
// comparison of MACs whose time does not depend on where they differ.
#include <array>
#include <cstdint>
#include <span>

namespace shapesense {

inline constexpr size_t kAuthKeyBytes = 32;  // 256-bit keys
inline constexpr size_t kMacBytes = 32;      // SHA-256
using Mac = std::array<uint8_t, kMacBytes>;

// HMAC-SHA256 of the concatenation of `parts` under `key`. Throws
// std::runtime_error only if libcrypto itself fails.
Mac HmacSha256(std::span<const uint8_t> key, std::span<const std::span<const uint8_t>> parts);

// Constant time (CRYPTO_memcmp).
bool MacsEqual(std::span<const uint8_t> a, std::span<const uint8_t> b);

}  // namespace shapesense
