// The serial line protocol's framing: the CRC-8 check value, round trips of
// random lines, every single-bit and single-byte error caught, and line
// assembly independent of how the bytes are chunked.
#include "libs/actuation/line_protocol.h"

#include <gtest/gtest.h>

#include <random>

namespace shapesense::serial_protocol {
namespace {

std::string RandomBody(std::mt19937& rng) {
  // Printable ASCII without '*' (the checksum separator) nor '\n'.
  std::uniform_int_distribution<int> length(0, 60);
  std::uniform_int_distribution<int> character(' ', '~');
  std::string body;
  for (int n = length(rng); static_cast<int>(body.size()) < n;) {
    const char c = static_cast<char>(character(rng));
    if (c != '*') body += c;
  }
  return body;
}

TEST(LineProtocolTest, Crc8HasTheCheckValueOfCrc8Smbus) {
  EXPECT_EQ(Crc8("123456789"), 0xF4);
  EXPECT_EQ(Crc8(""), 0x00);
  EXPECT_EQ(EncodeLine("P?"), "P?*" + std::string(1, "0123456789ABCDEF"[Crc8("P?") >> 4]) +
                                  std::string(1, "0123456789ABCDEF"[Crc8("P?") & 15]) + "\n");
}

TEST(LineProtocolTest, RandomLinesRoundTrip) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 500; ++trial) {
    const std::string body = RandomBody(rng);
    std::string line = EncodeLine(body);
    ASSERT_EQ(line.back(), '\n');
    line.pop_back();
    const DecodedLine decoded = DecodeLine(line);
    ASSERT_TRUE(decoded.ok()) << decoded.error;
    EXPECT_EQ(decoded.body, body);
    EXPECT_TRUE(DecodeLine(line + "\r").ok()) << "CR LF line ends are accepted";
  }
}

TEST(LineProtocolTest, EverySingleBitErrorIsCaught) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 100; ++trial) {
    std::string line = EncodeLine(RandomBody(rng));
    line.pop_back();
    for (size_t byte = 0; byte < line.size(); ++byte) {
      for (int bit = 0; bit < 7; ++bit) {  // ASCII: bit 7 would not be a character of a line
        std::string damaged = line;
        damaged[byte] = static_cast<char>(damaged[byte] ^ (1 << bit));
        if (damaged[byte] == '\n' || damaged[byte] == '\r') continue;
        EXPECT_FALSE(DecodeLine(damaged).ok())
            << "'" << line << "' byte " << byte << " bit " << bit;
      }
    }
  }
}

TEST(LineProtocolTest, EverySingleByteSubstitutionInTheBodyIsCaught) {
  std::mt19937 rng(13);
  std::uniform_int_distribution<int> character(' ', '~');
  for (int trial = 0; trial < 2000; ++trial) {
    const std::string body = RandomBody(rng);
    if (body.empty()) continue;
    std::string line = EncodeLine(body);
    line.pop_back();
    const size_t at = std::uniform_int_distribution<size_t>(0, body.size() - 1)(rng);
    const char replacement = static_cast<char>(character(rng));
    if (replacement == line[at] || replacement == '*') continue;
    line[at] = replacement;
    EXPECT_FALSE(DecodeLine(line).ok()) << line;
  }
}

TEST(LineProtocolTest, MalformedLinesSayWhy) {
  EXPECT_EQ(DecodeLine("P?").error, "no checksum");
  EXPECT_EQ(DecodeLine("P?*G1").error, "malformed checksum 'G1'");
  EXPECT_EQ(DecodeLine("P?*1").error, "malformed checksum '1'");
  std::string damaged = EncodeLine("X");
  damaged.pop_back();
  damaged[0] = 'Y';
  EXPECT_NE(DecodeLine(damaged).error.find("expected"), std::string::npos);
}

TEST(LineProtocolTest, WordsAndNumbers) {
  EXPECT_EQ(SplitWords("  T  2 -1.5 "), (std::vector<std::string>{"T", "2", "-1.5"}));
  EXPECT_EQ(FormatMm(-1.23456), "-1.2346");
  EXPECT_EQ(ParseNumber("+2.5"), 2.5);
  EXPECT_EQ(ParseNumber("-0.0001"), -0.0001);
  EXPECT_FALSE(ParseNumber("2.5mm"));
  EXPECT_FALSE(ParseNumber("nan"));
  EXPECT_FALSE(ParseNumber(""));
  EXPECT_EQ(ParseInteger("12"), 12);
  EXPECT_FALSE(ParseInteger("1.0"));
}

TEST(LineAssemblerTest, LinesDoNotDependOnHowTheBytesAreChunked) {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<std::string> sent;
    std::string stream;
    for (int i = 0; i < 10; ++i) {
      sent.push_back(RandomBody(rng));
      stream += sent.back() + "\n";
    }
    LineAssembler assembler;
    std::vector<std::string> received;
    for (size_t at = 0; at < stream.size();) {
      const size_t chunk = std::uniform_int_distribution<size_t>(1, 40)(rng);
      assembler.Feed(std::string_view(stream).substr(at, chunk), &received);
      at += chunk;
    }
    EXPECT_EQ(received, sent);
  }
}

TEST(LineAssemblerTest, AnOverlongLineIsDroppedWholeAndCounted) {
  LineAssembler assembler;
  std::vector<std::string> lines;
  assembler.Feed("A\n" + std::string(3 * kMaxLineBytes, 'x') + "\nB\n", &lines);
  EXPECT_EQ(lines, (std::vector<std::string>{"A", "B"}));
  EXPECT_EQ(assembler.overlong_lines(), 1);
}

}  // namespace
}  // namespace shapesense::serial_protocol
