// Key files on disk: `shapesense keygen` writes a new one of mode 0600 that
// reads back; an existing file is never overwritten; a key file group or
// others can read is refused, naming its mode and never the secret.
#include "runtime/security/key_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "clients/tools/keygen_command.h"
#include "libs/core/error.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;

class KeyFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) / ("key_file_test_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static std::string ErrorOf(const fs::path& path) {
    try {
      ReadKeyFile(path);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }

  fs::path dir_;
};

TEST_F(KeyFileTest, KeygenWritesAPrivateKeyThatReadsBack) {
  std::ostringstream log;
  const uint32_t id = RunKeygen(dir_ / "rig.key", 0, log);
  EXPECT_GT(id, 1'700'000'000u) << "the time in seconds";
  struct stat info {};
  ASSERT_EQ(stat((dir_ / "rig.key").c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0600u);
  const AuthKey key = ReadKeyFile(dir_ / "rig.key");
  EXPECT_EQ(key.id, id);
  EXPECT_NE(key.secret, AuthKey{}.secret);
  EXPECT_EQ(log.str().find(FormatKeyText(key).substr(FormatKeyText(key).rfind("secret: ") + 8, 16)),
            std::string::npos)
      << "the secret never shown";
  // Two keys differ.
  RunKeygen(dir_ / "next.key", id + 1, log);
  EXPECT_NE(ReadKeyFile(dir_ / "next.key").secret, key.secret);
  const KeyRing ring = ReadKeyRing({dir_ / "rig.key", dir_ / "next.key"});
  EXPECT_EQ(ring.signing().id, id + 1);
}

TEST_F(KeyFileTest, AnExistingFileIsNeverOverwritten) {
  std::ofstream(dir_ / "rig.key") << "precious";
  std::ostringstream log;
  EXPECT_THROW(RunKeygen(dir_ / "rig.key", 5, log), InputError);
  std::string kept;
  std::ifstream(dir_ / "rig.key") >> kept;
  EXPECT_EQ(kept, "precious");
}

TEST_F(KeyFileTest, AKeyOthersCanReadIsRefusedWithoutShowingIt) {
  const AuthKey key = NewAuthKey(3);
  WriteKeyFile(dir_ / "rig.key", key);
  ASSERT_EQ(chmod((dir_ / "rig.key").c_str(), 0644), 0);
  const std::string error = ErrorOf(dir_ / "rig.key");
  EXPECT_NE(error.find("0644"), std::string::npos) << error;
  EXPECT_NE(error.find("rig.key"), std::string::npos) << error;
  const std::string text = FormatKeyText(key);
  EXPECT_EQ(error.find(text.substr(text.rfind("secret: ") + 8, 16)), std::string::npos);
  ASSERT_EQ(chmod((dir_ / "rig.key").c_str(), 0640), 0);
  EXPECT_NE(ErrorOf(dir_ / "rig.key"), "");
  ASSERT_EQ(chmod((dir_ / "rig.key").c_str(), 0400), 0);
  EXPECT_EQ(ErrorOf(dir_ / "rig.key"), "");
  EXPECT_NE(ErrorOf(dir_ / "missing.key").find("missing.key"), std::string::npos);
  fs::create_symlink(dir_ / "rig.key", dir_ / "link.key");
  EXPECT_NE(ErrorOf(dir_ / "link.key"), "") << "a link could be swapped: refused";
}

}  // namespace
}  // namespace shapesense
