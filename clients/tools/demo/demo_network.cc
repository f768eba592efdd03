#include "clients/tools/demo/demo_network.h"

#include <fcntl.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "clients/tools/demo/demo_processes.h"
#include "runtime/process/private_network.h"

namespace shapesense {
namespace {

ino_t NetworkNamespaceId() {
  struct stat info {};
  return stat("/proc/self/ns/net", &info) == 0 ? info.st_ino : 0;
}

// EnterPrivateNetwork, undone when it fails after it left the host's
// network (e.g. `ip` failed in the new namespace): "" or why it failed.
std::string EnterOrStay(int addresses) {
  if (FindOnPath("ip").empty()) return "the `ip` tool (Debian package iproute2) is missing";
  const int host = open("/proc/self/ns/net", O_RDONLY | O_CLOEXEC);
  const ino_t host_id = NetworkNamespaceId();
  std::string error = EnterPrivateNetwork(addresses - 1);
  if (!error.empty() && NetworkNamespaceId() != host_id &&
      (host < 0 || setns(host, CLONE_NEWNET) != 0)) {
    throw std::runtime_error(error + "; and cannot go back to the host's network (" +
                             std::strerror(errno) + ")");
  }
  if (host >= 0) close(host);
  return error;
}

}  // namespace

DemoNetwork EnterDemoNetwork(DemoNetworkMode mode, int addresses) {
  if (mode == DemoNetworkMode::kCurrent) return {false, "--network current"};
  const std::string error = EnterOrStay(addresses);
  if (error.empty()) return {true, ""};
  if (mode == DemoNetworkMode::kPrivate) throw std::runtime_error(error);
  return {false, error};
}

}  // namespace shapesense
