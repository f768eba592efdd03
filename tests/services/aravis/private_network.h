#pragma once

// Tests that talk over the network (GigE Vision, LCM multicast) run inside a
// private network namespace the test binary makes for itself, so nothing
// leaves the machine and parallel tests do not see each other.

#include <string>

namespace shapesense::nettest {

// Moves this process (and every child it starts later) into a new network
// namespace: unshare(CLONE_NEWNET) as root, else together with a user
// namespace that maps the caller to root. Then brings loopback up with
// multicast, routes 224.0.0.0/4 to it (LCM's udpm), and gives it the
// addresses 127.0.0.2 ... 127.0.0.(1 + extra_addresses) (a fake GigE camera
// binds to an address an interface has). Must be called while the process has
// a single thread (first thing in main). Returns "" or why it failed.
std::string EnterPrivateNetwork(int extra_addresses);

// The outcome of the call in the test main (see private_network_main.cc).
const std::string& PrivateNetworkError();

// "127.0.0.<1 + index>".
std::string LoopbackAddress(int index);

}  // namespace shapesense::nettest
