#pragma once

// A private network namespace for multi-process work on one machine (the
// network tests, the latency bench, the demo): LCM's UDP multicast and the
// fake GigE cameras stay inside it, and parallel runs do not see each other.

#include <string>

namespace shapesense {

// Moves this process (and every child it starts later) into a new network
// namespace: unshare(CLONE_NEWNET) as root, else together with a user
// namespace that maps the caller to root. Then brings loopback up with
// multicast, routes 224.0.0.0/4 to it (LCM's udpm), and gives it the
// addresses 127.0.0.2 ... 127.0.0.(1 + extra_addresses) (a fake GigE camera
// binds to an address an interface has). Must be called while the process has
// a single thread (first thing in main). Returns "" or why it failed, in which
// case the process may be left in a namespace without a working loopback.
std::string EnterPrivateNetwork(int extra_addresses);

// "127.0.0.<1 + index>".
std::string LoopbackAddress(int index);

enum class NetworkMode {
  kAuto,     // a private namespace where possible, else the host's network
  kPrivate,  // a private namespace, or fail
  kCurrent,  // the network this process is in (e.g. a namespace it is in already)
};

struct NetworkChoice {
  bool private_namespace = false;  // entered one
  std::string why_not;             // when not: why
};

// Enters a private network namespace with loopback addresses 127.0.0.1 ...
// 127.0.0.`addresses` (one per fake camera), for kAuto and kPrivate: a private namespace when
// the caller can make one (LCM and the fake GigE cameras stay inside it, and
// other runs on the machine neither see nor disturb it), else the host's
// network with LCM's host-only default (ttl=0). Call it
// while the process has one thread (before anything starts one). When it
// fails half-way, goes back to the host's network. Throws std::runtime_error
// for kPrivate when it fails, and when it cannot go back.
NetworkChoice EnterNetwork(NetworkMode mode, int addresses);

}  // namespace shapesense
