// Key files' text read back exactly; every mistake named without the
// secret; a ring of at most two keys (rotation), found by id; replay
// windows by counter.
#include "libs/security/auth_key.h"

#include <gtest/gtest.h>

#include "libs/core/error.h"
#include "libs/security/replay_window.h"
#include "tests/libs/security/test_keys.h"

namespace shapesense {
namespace {

// The message of the InputError `text` gets, "" when none.
std::string ErrorOf(const std::string& text) {
  try {
    ParseKeyText(text, "rig.key");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(AuthKeyTest, ItsTextReadsBackExactly) {
  const AuthKey key = testing::TestKey(7, 0xa5);
  const AuthKey back = ParseKeyText(FormatKeyText(key), "rig.key");
  EXPECT_EQ(back.id, 7u);
  EXPECT_EQ(back.secret, key.secret);
}

TEST(AuthKeyTest, MistakesAreNamedButTheSecretIsNever) {
  const std::string short_secret(63, 'c');
  const std::string secret = short_secret + "c";
  const std::string password = "password: " + short_secret + "\n";
  const std::string good = "key_id: 1\nsecret: " + secret + "\n";
  for (const std::string& text :
       {"key_id: 1\nsecret: " + short_secret + "\n", "key_id: 1\nsecret: " + short_secret + "z\n",
        "key_id: x1\nsecret: " + secret + "\n", "secret: " + secret + "\n",
        std::string("key_id: 1\n"), good + password}) {
    const std::string error = ErrorOf(text);
    EXPECT_NE(error, "") << text;
    EXPECT_NE(error.find("rig.key"), std::string::npos) << error;
    EXPECT_EQ(error.find("cccccccc"), std::string::npos) << "the secret shown: " << error;
  }
}

TEST(AuthKeyTest, ARingHoldsTheCurrentKeyAndTheOneItReplaces) {
  const KeyRing ring({testing::TestKey(1, 1), testing::TestKey(2, 2)});
  EXPECT_EQ(ring.signing().id, 2u);
  ASSERT_NE(ring.Find(1), nullptr);
  EXPECT_EQ(ring.Find(1)->secret, testing::TestKey(1, 1).secret);
  EXPECT_EQ(ring.Find(3), nullptr);
  EXPECT_THROW(KeyRing({}), InputError);
  EXPECT_THROW(KeyRing({testing::TestKey(1, 1), testing::TestKey(2, 2), testing::TestKey(3, 3)}),
               InputError);
  EXPECT_THROW(KeyRing({testing::TestKey(1, 1), testing::TestKey(1, 2)}), InputError);
}

TEST(ReplayWindowTest, FreshOnceWithinTheWindowReplayedAfterTooOldBelowIt) {
  using Verdict = ReplayWindow::Verdict;
  ReplayWindow window;
  EXPECT_EQ(window.Accept(1000), Verdict::kFresh);
  EXPECT_EQ(window.Accept(1000), Verdict::kReplayed);
  EXPECT_EQ(window.Accept(1002), Verdict::kFresh);
  EXPECT_EQ(window.Accept(1001), Verdict::kFresh);  // reordered, not seen
  EXPECT_EQ(window.Accept(1001), Verdict::kReplayed);
  EXPECT_EQ(window.Check(1002 - 63), Verdict::kFresh);  // the window's oldest
  EXPECT_EQ(window.Check(1002 - 64), Verdict::kTooOld);
  // A jump ahead (a sender restarted later) moves the window past all before.
  EXPECT_EQ(window.Accept(50'000), Verdict::kFresh);
  EXPECT_EQ(window.Accept(1002), Verdict::kTooOld);
  EXPECT_EQ(window.Accept(49'999), Verdict::kFresh);
  // Check changes nothing.
  EXPECT_EQ(window.Check(49'998), Verdict::kFresh);
  EXPECT_EQ(window.Check(49'998), Verdict::kFresh);
}

}  // namespace
}  // namespace shapesense
