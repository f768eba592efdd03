#pragma once

// The serial actuator line protocol (docs/actuators.md): ASCII lines
// "<body>*<HH>\n", HH the CRC-8 of the body in upper-case hex. Pure
// functions, shared by the driver and the simulated actuator.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace shapesense::serial_protocol {

// Longest line either side sends or accepts, '\n' included; a longer one is
// dropped whole.
constexpr size_t kMaxLineBytes = 256;

// The device's error codes ("E <code> <text>").
enum class DeviceError {
  kChecksum = 1,  // the line's checksum was wrong: nothing was done, send it again
  kSyntax = 2,    // unknown command or malformed arguments
  kAxis = 3,      // no such axis
  kRange = 4,     // target outside the axis's travel
  kFaulted = 5,   // the actuator is in a fault: no target is taken until R clears it
};

// CRC-8, polynomial 0x07, initial value 0, no reflection (CRC-8/SMBUS):
// "123456789" → 0xF4.
uint8_t Crc8(std::string_view bytes);

// "<body>*<HH>\n".
std::string EncodeLine(std::string_view body);

struct DecodedLine {
  std::string body;  // without the checksum
  std::string
      error;  // empty when the line is valid: "no checksum", "checksum 3A, expected 3B", ...
  bool ok() const { return error.empty(); }
};
// Checks one received line, without its '\n' (a trailing '\r' is ignored).
DecodedLine DecodeLine(std::string_view line);

// Words separated by single or repeated spaces.
std::vector<std::string> SplitWords(std::string_view body);
// A millimetre value as the protocol writes it: fixed, 4 decimals.
std::string FormatMm(double mm);
// A whole word as a finite number / an integer; nullopt otherwise.
std::optional<double> ParseNumber(std::string_view word);
std::optional<int> ParseInteger(std::string_view word);

// Cuts a byte stream into lines. Bytes of a line longer than kMaxLineBytes
// are dropped up to the next '\n' and counted.
class LineAssembler {
 public:
  // Appends every complete line in `bytes` (without '\n') to `lines`.
  void Feed(std::string_view bytes, std::vector<std::string>* lines);
  void Clear();
  int64_t overlong_lines() const { return overlong_lines_; }

 private:
  std::string partial_;
  bool discarding_ = false;
  int64_t overlong_lines_ = 0;
};

}  // namespace shapesense::serial_protocol
