#include "runtime/lcm/lcm_url.h"

#include <stdexcept>
#include <vector>

namespace shapesense {
namespace {

constexpr const char* kUdpm = "udpm://";

std::vector<std::string> SplitOptions(const std::string& options) {
  std::vector<std::string> items;
  size_t start = options.empty() ? 0 : 1;  // past '?'
  while (start < options.size()) {
    const size_t end = options.find('&', start);
    items.push_back(options.substr(start, end - start));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return items;
}

}  // namespace

bool IsUdpm(const std::string& url) { return url.rfind(kUdpm, 0) == 0; }

UdpmUrl SplitUdpm(const std::string& url) {
  UdpmUrl parts;
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
  if (used == 0 || used != port.size() || parts.port <= 0 || parts.port > 65535) {
    throw std::invalid_argument("LCM URL '" + url + "': expected a port number, got '" + port +
                                "'");
  }
  return parts;
}

std::string JoinUdpm(const UdpmUrl& parts) {
  return kUdpm + parts.group + ":" + std::to_string(parts.port) + parts.options;
}

int TtlOf(const std::string& url) {
  if (!IsUdpm(url)) return 0;
  for (const std::string& option : SplitOptions(SplitUdpm(url).options)) {
    if (option.rfind("ttl=", 0) == 0) return std::stoi(option.substr(4));
  }
  return 0;
}

std::string WithTtl(const std::string& url, int ttl) {
  if (!IsUdpm(url)) return url;
  UdpmUrl parts = SplitUdpm(url);
  std::string options = "?ttl=" + std::to_string(ttl);
  for (const std::string& option : SplitOptions(parts.options)) {
    if (option.rfind("ttl=", 0) != 0) options += "&" + option;
  }
  parts.options = options;
  return JoinUdpm(parts);
}

std::string GroupAndPort(const std::string& url) {
  if (!IsUdpm(url)) return url;
  const UdpmUrl parts = SplitUdpm(url);
  return parts.group + ":" + std::to_string(parts.port);
}

}  // namespace shapesense
