// HMAC-SHA256 as RFC 4231 defines it (test cases 1, 2 and 6), over parts as
// over their concatenation; MACs compared whole.
#include "libs/security/hmac.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace shapesense {
namespace {

std::span<const uint8_t> Bytes(const std::string& text) {
  return {reinterpret_cast<const uint8_t*>(text.data()), text.size()};
}

std::string Hex(const Mac& mac) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  for (const uint8_t byte : mac) {
    hex += kHex[byte >> 4];
    hex += kHex[byte & 15];
  }
  return hex;
}

Mac Of(const std::string& key, const std::string& data) {
  const std::vector<std::span<const uint8_t>> parts = {Bytes(data)};
  return HmacSha256(Bytes(key), parts);
}

TEST(HmacTest, MatchesRfc4231) {
  EXPECT_EQ(Hex(Of(std::string(20, '\x0b'), "Hi There")),
            "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7");
  EXPECT_EQ(Hex(Of("Jefe", "what do ya want for nothing?")),
            "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
  // A key longer than the block: hashed first.
  EXPECT_EQ(
      Hex(Of(std::string(131, '\xaa'), "Test Using Larger Than Block-Size Key - Hash Key First")),
      "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54");
}

TEST(HmacTest, PartsAreTheirConcatenation) {
  const std::string key = "k";
  const std::string first = "what do ya ";
  const std::string second = "want for nothing?";
  const std::vector<std::span<const uint8_t>> parts = {Bytes(first), Bytes(second)};
  EXPECT_EQ(HmacSha256(Bytes(key), parts), Of(key, "what do ya want for nothing?"));
}

TEST(HmacTest, MacsAreEqualOnlyWhole) {
  const Mac a = Of("key", "message");
  Mac b = a;
  EXPECT_TRUE(MacsEqual(a, b));
  b[31] ^= 1;
  EXPECT_FALSE(MacsEqual(a, b));
  EXPECT_FALSE(MacsEqual(a, std::span<const uint8_t>(a).first(16)));
}

}  // namespace
}  // namespace shapesense
