#pragma once

// Where the live demo's programs talk: a private network namespace when the
// demo can make one (LCM and the fake GigE cameras stay inside it, and other
// runs on the machine neither see nor disturb it), else the host's network
// with LCM's host-only default (ttl=0).
#include <string>

namespace shapesense {

enum class DemoNetworkMode {
  kAuto,     // a private namespace where possible, else the host's network
  kPrivate,  // a private namespace, or fail
  kCurrent,  // the network this process is in (e.g. a namespace it is in already)
};

struct DemoNetwork {
  bool private_namespace = false;  // entered one
  std::string why_not;             // when not: why
};

// Enters a private network namespace with loopback addresses 127.0.0.1 ...
// 127.0.0.`addresses` (one per fake camera), for kAuto and kPrivate. Call it
// while the process has one thread (before anything starts one). When it
// fails half-way, goes back to the host's network. Throws std::runtime_error
// for kPrivate when it fails, and when it cannot go back.
DemoNetwork EnterDemoNetwork(DemoNetworkMode mode, int addresses);

}  // namespace shapesense
