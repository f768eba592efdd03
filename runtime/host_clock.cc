#include "runtime/host_clock.h"

#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace shapesense {
namespace {

int64_t ReadTestClockOffsetUs() {
  const char* text = std::getenv(kTestClockOffsetVariable);
  if (text == nullptr || *text == 0) return 0;
  char* end = nullptr;
  const double ms = std::strtod(text, &end);
  if (end == text || *end != 0 || !std::isfinite(ms)) {
    throw std::invalid_argument(std::string(kTestClockOffsetVariable) + "='" + text +
                                "': expected a number of milliseconds");
  }
  return std::llround(ms * 1000.0);
}

}  // namespace

int64_t TestClockOffsetUs() {
  static const int64_t offset = ReadTestClockOffsetUs();
  return offset;
}

int64_t HostUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
             .count() +
         TestClockOffsetUs();
}

std::string HostName() {
  std::array<char, 256> name{};
  if (gethostname(name.data(), name.size() - 1) != 0 || name[0] == 0) return "unknown";
  return name.data();
}

}  // namespace shapesense
