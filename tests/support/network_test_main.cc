// The main of network tests: enters a private network namespace before
// anything starts a thread, then runs the tests. Listing the tests (CMake's
// test discovery at build time) needs no namespace. A failure to make one is
// kept for the tests to fail with (PrivateNetworkError), not skipped.

#include <gtest/gtest.h>

#include "runtime/process/private_network.h"
#include "tests/support/network_test.h"

namespace shapesense::nettest {
namespace {

std::string& ErrorSlot() {
  static std::string error = "the private network namespace was not entered";
  return error;
}

}  // namespace

const std::string& PrivateNetworkError() { return ErrorSlot(); }

}  // namespace shapesense::nettest

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  if (!GTEST_FLAG_GET(list_tests)) {
    shapesense::nettest::ErrorSlot() = shapesense::EnterPrivateNetwork(8);
  }
  return RUN_ALL_TESTS();
}
