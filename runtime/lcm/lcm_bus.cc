#include "runtime/lcm/lcm_bus.h"

#include <chrono>
#include <cstdlib>
#include <stdexcept>

namespace shapesense {

LcmBus::LcmBus(const std::string& url) : url_(ResolveLcmUrl(url)), lcm_(url_) {
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

std::string ResolveLcmUrl(const std::string& url) {
  if (!url.empty()) return url;
  const char* environment = std::getenv("LCM_DEFAULT_URL");
  return environment != nullptr && *environment != 0 ? environment
                                                     : "udpm://239.255.76.67:7667?ttl=0";
}

int64_t NowUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace shapesense
