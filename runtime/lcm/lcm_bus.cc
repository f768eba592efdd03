#include "runtime/lcm/lcm_bus.h"

#include <chrono>
#include <stdexcept>

namespace shapesense {

LcmBus::LcmBus(const std::string& url) : lcm_(url) {
  if (!lcm_.good()) {
    throw std::runtime_error(
        "LCM could not start on '" + (url.empty() ? std::string("default") : url) +
        "' (is there a multicast route? see docs/capture.md, section LCM on a rig)");
  }
}

void LcmBus::Reject(const std::string& channel, const std::string& why) {
  ++rejected_;
  last_rejection_ = channel + ": " + why;
}

int64_t NowUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace shapesense
