#pragma once

// LCM provider URLs of the UDP multicast kind, udpm://GROUP:PORT?OPTIONS:
// taken apart and put back together, for the image ports (image_buses.h)
// and the host-local network (lcm_bus.h).
#include <string>

namespace shapesense {

inline constexpr int kLcmDefaultPort = 7667;

struct UdpmUrl {
  std::string group;
  int port = kLcmDefaultPort;
  std::string options;  // "?ttl=1&recv_buf_size=..." or ""
};

bool IsUdpm(const std::string& url);
// Throws std::invalid_argument naming the URL when its port is not a number.
UdpmUrl SplitUdpm(const std::string& url);
std::string JoinUdpm(const UdpmUrl& parts);

// The ttl a udpm URL sets (LCM's default 0 when absent); 0 for any other
// provider (memq://, file://: nothing leaves the process or host).
int TtlOf(const std::string& url);
// `url` with its ttl set to `ttl` (other options kept); other providers as they are.
std::string WithTtl(const std::string& url, int ttl);
// group:port, the part of a udpm URL that decides which sockets receive.
std::string GroupAndPort(const std::string& url);

}  // namespace shapesense
