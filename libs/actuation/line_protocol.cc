#include "libs/actuation/line_protocol.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>

namespace shapesense::serial_protocol {
namespace {

constexpr char kHexDigits[] = "0123456789ABCDEF";

// Two upper-case hex digits, as the protocol writes them (and nothing else:
// "3a" for "3A" would let a flipped case bit through).
std::optional<uint8_t> ParseHexByte(std::string_view text) {
  if (text.size() != 2) return std::nullopt;
  int value = 0;
  for (const char c : text) {
    const char* digit = std::char_traits<char>::find(kHexDigits, 16, c);
    if (!digit) return std::nullopt;
    value = value * 16 + static_cast<int>(digit - kHexDigits);
  }
  return static_cast<uint8_t>(value);
}

std::string HexByte(uint8_t value) { return {kHexDigits[value >> 4], kHexDigits[value & 0x0F]}; }

}  // namespace

uint8_t Crc8(std::string_view bytes) {
  uint8_t crc = 0;
  for (const char c : bytes) {
    crc ^= static_cast<uint8_t>(c);
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x80) ? static_cast<uint8_t>((crc << 1) ^ 0x07) : static_cast<uint8_t>(crc << 1);
    }
  }
  return crc;
}

std::string EncodeLine(std::string_view body) {
  std::string line(body);
  line += '*';
  line += HexByte(Crc8(body));
  line += '\n';
  return line;
}

DecodedLine DecodeLine(std::string_view line) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  const size_t star = line.rfind('*');
  if (star == std::string_view::npos) return {"", "no checksum"};
  const std::string_view body = line.substr(0, star);
  const std::optional<uint8_t> given = ParseHexByte(line.substr(star + 1));
  if (!given) return {"", "malformed checksum '" + std::string(line.substr(star + 1)) + "'"};
  const uint8_t expected = Crc8(body);
  if (*given != expected) {
    return {"", "checksum " + HexByte(*given) + ", expected " + HexByte(expected)};
  }
  return {std::string(body), ""};
}

std::vector<std::string> SplitWords(std::string_view body) {
  std::vector<std::string> words;
  size_t start = 0;
  while (start < body.size()) {
    const size_t end = body.find(' ', start);
    const size_t stop = end == std::string_view::npos ? body.size() : end;
    if (stop > start) words.emplace_back(body.substr(start, stop - start));
    start = stop + 1;
  }
  return words;
}

std::string FormatMm(double mm) {
  char text[48];
  std::snprintf(text, sizeof(text), "%.4f", mm);
  return text;
}

std::optional<double> ParseNumber(std::string_view word) {
  double value = 0.0;
  if (!word.empty() && word.front() == '+') word.remove_prefix(1);
  const auto result = std::from_chars(word.data(), word.data() + word.size(), value);
  if (word.empty() || result.ec != std::errc() || result.ptr != word.data() + word.size() ||
      !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

std::optional<int> ParseInteger(std::string_view word) {
  int value = 0;
  const auto result = std::from_chars(word.data(), word.data() + word.size(), value);
  if (word.empty() || result.ec != std::errc() || result.ptr != word.data() + word.size()) {
    return std::nullopt;
  }
  return value;
}

void LineAssembler::Feed(std::string_view bytes, std::vector<std::string>* lines) {
  for (const char c : bytes) {
    if (c == '\n') {
      if (!discarding_) lines->push_back(partial_);
      partial_.clear();
      discarding_ = false;
    } else if (!discarding_) {
      partial_ += c;
      if (partial_.size() >= kMaxLineBytes) {
        // Too long to be a line of the protocol: drop it up to its end.
        partial_.clear();
        discarding_ = true;
        ++overlong_lines_;
      }
    }
  }
}

void LineAssembler::Clear() {
  partial_.clear();
  discarding_ = false;
}

}  // namespace shapesense::serial_protocol
