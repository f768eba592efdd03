#include "runtime/lcm/image_buses.h"

#include <stdexcept>

#include "runtime/lcm/lcm_url.h"

namespace shapesense {

bool HasImageBuses(const std::string& url) { return IsUdpm(url); }

std::string ImageUrl(const std::string& url, size_t camera_index) {
  if (!HasImageBuses(url)) return url;
  UdpmUrl parts = SplitUdpm(url);
  const size_t port = static_cast<size_t>(parts.port) + 1 + camera_index;
  if (port > 65535) {
    throw std::invalid_argument("LCM URL '" + url + "': camera " + std::to_string(camera_index) +
                                "'s image port " + std::to_string(port) + " is past 65535");
  }
  parts.port = static_cast<int>(port);
  return JoinUdpm(parts);
}

ImageBuses::ImageBuses(LcmBus& main, size_t cameras) : main_(main) {
  if (HasImageBuses(main.local_url())) own_.resize(cameras);
}

LcmBus& ImageBuses::ForCamera(size_t camera_index) {
  if (own_.empty()) return main_;
  std::unique_ptr<LcmBus>& bus = own_.at(camera_index);
  if (!bus) {
    LcmBusOptions options = main_.options();
    options.url = ImageUrl(main_.local_url(), camera_index);
    options.local_url = options.url;  // an image bus is local, whole
    bus = std::make_unique<LcmBus>(options);
  }
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
