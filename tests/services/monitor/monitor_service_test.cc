// The e-stop token: read only from a private file of one long line, and
// compared in full.
#include "services/monitor/monitor_service.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "libs/core/error.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;

fs::path TokenFile(const std::string& text, mode_t mode) {
  fs::path path = fs::temp_directory_path() / ("estop_token_" + std::to_string(getpid()));
  fs::remove(path);
  std::ofstream(path) << text;
  chmod(path.c_str(), mode);
  return path;
}

TEST(EstopTokenTest, ReadOnlyFromAPrivateFileOfOneLongLine) {
  EXPECT_EQ(ReadEstopToken(TokenFile("0123456789abcdef-token\n", 0600)), "0123456789abcdef-token");
  EXPECT_THROW(ReadEstopToken(TokenFile("0123456789abcdef-token\n", 0644)), InputError);
  EXPECT_THROW(ReadEstopToken(TokenFile("short\n", 0600)), InputError);
  EXPECT_THROW(ReadEstopToken(TokenFile("0123456789abcdef\nsecond line\n", 0600)), InputError);
  EXPECT_THROW(ReadEstopToken("/nonexistent/estop.token"), InputError);
  fs::remove(TokenFile("", 0600));
}

TEST(EstopTokenTest, MatchesOnlyTheWholeToken) {
  const std::string token = "0123456789abcdef-token";
  EXPECT_TRUE(TokenMatches(token, token));
  EXPECT_FALSE(TokenMatches(token, token.substr(0, 16)));
  EXPECT_FALSE(TokenMatches(token, token + "x"));
  EXPECT_FALSE(TokenMatches(token, "1123456789abcdef-token"));
  EXPECT_FALSE(TokenMatches(token, ""));
}

}  // namespace
}  // namespace shapesense
