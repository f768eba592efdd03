#include "runtime/lcm/image_buses.h"

#include <stdexcept>

namespace shapesense {
namespace {

constexpr const char* kUdpm = "udpm://";
constexpr int kLcmDefaultPort = 7667;

struct UdpmParts {
  std::string group;
  int port = kLcmDefaultPort;
  std::string options;  // "?..." or ""
};

UdpmParts SplitUdpm(const std::string& url) {
  UdpmParts parts;
  const std::string rest = url.substr(std::string(kUdpm).size());
  const size_t query = rest.find('?');
  const std::string address = rest.substr(0, query);
  if (query != std::string::npos) parts.options = rest.substr(query);
  const size_t colon = address.rfind(':');
  parts.group = address.substr(0, colon);
  if (colon == std::string::npos) return parts;
  const std::string port = address.substr(colon + 1);
  size_t used = 0;
  try {
    parts.port = std::stoi(port, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != port.size() || parts.port <= 0) {
    throw std::invalid_argument("LCM URL '" + url + "': expected a port number, got '" + port +
                                "'");
  }
  return parts;
}

}  // namespace

bool HasImageBuses(const std::string& url) { return url.rfind(kUdpm, 0) == 0; }

std::string ImageUrl(const std::string& url, size_t camera_index) {
  if (!HasImageBuses(url)) return url;
  const UdpmParts parts = SplitUdpm(url);
  const size_t port = static_cast<size_t>(parts.port) + 1 + camera_index;
  if (port > 65535) {
    throw std::invalid_argument("LCM URL '" + url + "': camera " + std::to_string(camera_index) +
                                "'s image port " + std::to_string(port) + " is past 65535");
  }
  return kUdpm + parts.group + ":" + std::to_string(port) + parts.options;
}

ImageBuses::ImageBuses(LcmBus& main, size_t cameras) : main_(main) {
  if (HasImageBuses(main.url())) own_.resize(cameras);
}

LcmBus& ImageBuses::ForCamera(size_t camera_index) {
  if (own_.empty()) return main_;
  std::unique_ptr<LcmBus>& bus = own_.at(camera_index);
  if (!bus) bus = std::make_unique<LcmBus>(ImageUrl(main_.url(), camera_index));
  return *bus;
}

std::vector<LcmBus*> ImageBuses::Opened() const {
  std::vector<LcmBus*> opened;
  for (const std::unique_ptr<LcmBus>& bus : own_) {
    if (bus) opened.push_back(bus.get());
  }
  return opened;
}

}  // namespace shapesense
