// Signing and verifying a message's bytes: the signed message is accepted
// once; a replay, another channel, an unknown key, an unsigned message and
// any single flipped bit are rejected and counted by reason; a key being
// rotated out still verifies.
#include "libs/security/message_auth.h"

#include <gtest/gtest.h>

#include <vector>

#include "tests/libs/security/test_keys.h"

namespace shapesense {
namespace {

// A stand-in for an encoded message: 8 bytes of fingerprint, a body, the
// MAC field, more body.
struct Signed {
  AuthTag tag;
  std::vector<uint8_t> bytes;
  size_t mac_offset = 0;
};

Signed Sign(MessageSigner& signer, const std::string& channel) {
  Signed message;
  message.tag = signer.Next();
  for (int i = 0; i < 40; ++i) message.bytes.push_back(static_cast<uint8_t>(i * 7));
  message.mac_offset = message.bytes.size();
  message.bytes.resize(message.bytes.size() + kMacBytes, 0);
  for (int i = 0; i < 20; ++i)
    message.bytes.push_back(static_cast<uint8_t>(message.tag.counter + i));
  const Mac mac = signer.Sign(channel, message.tag, message.bytes, message.mac_offset);
  std::copy(mac.begin(), mac.end(), message.bytes.begin() + static_cast<long>(message.mac_offset));
  return message;
}

std::optional<AuthRejection> Verify(MessageVerifier& verifier, const std::string& channel,
                                    const Signed& message) {
  return verifier.Verify(channel, message.tag, message.bytes, message.mac_offset);
}

TEST(MessageAuthTest, ASignedMessageIsAcceptedOnceAndOnItsChannelOnly) {
  MessageSigner signer(KeyRing({testing::TestKey(1, 0x11)}), "control/controller", 1000);
  MessageVerifier verifier(KeyRing({testing::TestKey(1, 0x11)}));
  const Signed first = Sign(signer, "SHAPESENSE_TARGET");
  EXPECT_EQ(Verify(verifier, "SHAPESENSE_TARGET", first), std::nullopt);
  EXPECT_EQ(Verify(verifier, "SHAPESENSE_TARGET", first), AuthRejection::kReplayed);
  const Signed second = Sign(signer, "SHAPESENSE_TARGET");
  EXPECT_EQ(Verify(verifier, "SHAPESENSE_PLANT_COMMAND", second), AuthRejection::kBadMac);
  EXPECT_EQ(Verify(verifier, "SHAPESENSE_TARGET", second), std::nullopt);
  EXPECT_EQ(verifier.accepted(), 2);
  EXPECT_EQ(verifier.rejections().at("replayed"), 1);
  EXPECT_EQ(verifier.rejections().at("bad_mac"), 1);
}

TEST(MessageAuthTest, UnsignedUnknownKeysAndForgedTagsAreRejected) {
  MessageSigner signer(KeyRing({testing::TestKey(1, 0x11)}), "operator/demo", 1);
  MessageSigner stranger(KeyRing({testing::TestKey(9, 0x99)}), "operator/demo", 1);
  MessageVerifier verifier(KeyRing({testing::TestKey(1, 0x11)}));
  Signed message = Sign(signer, "C");
  Signed unsigned_message = message;
  unsigned_message.tag.sender.clear();
  EXPECT_EQ(Verify(verifier, "C", unsigned_message), AuthRejection::kUnsigned);
  EXPECT_EQ(Verify(verifier, "C", Sign(stranger, "C")), AuthRejection::kUnknownKey);
  // A signed message with a byte of its body changed: a forgery.
  Signed forged = Sign(signer, "C");
  forged.bytes.back() ^= 0x40;
  EXPECT_EQ(Verify(verifier, "C", forged), AuthRejection::kBadMac);
  // A forgery never moves the window: the real message is still fresh.
  EXPECT_EQ(Verify(verifier, "C", message), std::nullopt);
  Signed truncated = message;
  truncated.bytes.resize(message.mac_offset + 10);
  EXPECT_EQ(Verify(verifier, "C", truncated), AuthRejection::kMalformed);
}

TEST(MessageAuthTest, EverySingleBitFlipIsRejected) {
  MessageSigner signer(KeyRing({testing::TestKey(1, 0x11)}), "camera/shape", 1);
  const Signed message = Sign(signer, "SHAPESENSE_SHAPE");
  for (size_t bit = 0; bit < message.bytes.size() * 8; ++bit) {
    MessageVerifier verifier(KeyRing({testing::TestKey(1, 0x11)}));
    Signed flipped = message;
    flipped.bytes[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
    EXPECT_EQ(Verify(verifier, "SHAPESENSE_SHAPE", flipped), AuthRejection::kBadMac) << bit;
  }
}

TEST(MessageAuthTest, DuringARotationBothKeysVerifyAndTheNewOneSigns) {
  MessageSigner old_signer(KeyRing({testing::TestKey(1, 0x11)}), "control/controller", 1);
  MessageSigner new_signer(KeyRing({testing::TestKey(1, 0x11), testing::TestKey(2, 0x22)}),
                           "operator/demo", 1);
  MessageVerifier verifier(KeyRing({testing::TestKey(1, 0x11), testing::TestKey(2, 0x22)}));
  const Signed old_message = Sign(old_signer, "C");
  const Signed new_message = Sign(new_signer, "C");
  EXPECT_EQ(new_message.tag.key_id, 2u);
  EXPECT_EQ(Verify(verifier, "C", old_message), std::nullopt);
  EXPECT_EQ(Verify(verifier, "C", new_message), std::nullopt);
  MessageVerifier rotated(KeyRing({testing::TestKey(2, 0x22)}));
  EXPECT_EQ(Verify(rotated, "C", Sign(old_signer, "C")), AuthRejection::kUnknownKey);
}

}  // namespace
}  // namespace shapesense
