#pragma once

// Network tests (GigE Vision, LCM multicast) link network_test_main.cc, which
// moves the test binary into a private network namespace of its own before
// any thread starts (runtime/process/private_network.h).

#include <string>

namespace shapesense::nettest {

// Why the namespace could not be made, or "". A test that needs the network
// asserts it is empty: it fails, never skips.
const std::string& PrivateNetworkError();

}  // namespace shapesense::nettest
