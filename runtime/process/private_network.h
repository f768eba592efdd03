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

}  // namespace shapesense
