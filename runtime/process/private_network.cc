#include "runtime/process/private_network.h"

#include <fcntl.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "runtime/process/process_group.h"

namespace shapesense {
namespace {

bool WriteProcFile(const std::string& path, const std::string& text) {
  std::ofstream file(path);
  file << text;
  return static_cast<bool>(file.flush());
}

// Without root: a user namespace in which this process is root, which owns
// the new network namespace.
std::string UnshareAsUser() {
  const unsigned uid = getuid();
  const unsigned gid = getgid();
  if (unshare(CLONE_NEWUSER | CLONE_NEWNET) != 0) {
    return std::string("unshare(CLONE_NEWUSER | CLONE_NEWNET) failed: ") + std::strerror(errno) +
           " (user namespaces not permitted here; run the tests as root)";
  }
  if (!WriteProcFile("/proc/self/setgroups", "deny") ||
      !WriteProcFile("/proc/self/uid_map", "0 " + std::to_string(uid) + " 1") ||
      !WriteProcFile("/proc/self/gid_map", "0 " + std::to_string(gid) + " 1")) {
    return "cannot map the user into the new user namespace";
  }
  return "";
}

std::string Run(const std::string& command) {
  const int status = std::system((command + " 2>&1").c_str());
  if (status == 0) return "";
  return "'" + command + "' failed (status " + std::to_string(status) + ")";
}

}  // namespace

std::string LoopbackAddress(int index) { return "127.0.0." + std::to_string(1 + index); }

std::string EnterPrivateNetwork(int extra_addresses) {
  std::string error;
  if (unshare(CLONE_NEWNET) != 0) error = UnshareAsUser();
  if (error.empty()) error = Run("ip link set lo up && ip link set lo multicast on");
  if (error.empty()) error = Run("ip route add 224.0.0.0/4 dev lo");
  for (int i = 1; i <= extra_addresses && error.empty(); ++i) {
    error = Run("ip addr add " + LoopbackAddress(i) + "/8 dev lo");
  }
  return error.empty() ? "" : "private network namespace: " + error;
}

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

NetworkChoice EnterNetwork(NetworkMode mode, int addresses) {
  if (mode == NetworkMode::kCurrent) return {false, "--network current"};
  const std::string error = EnterOrStay(addresses);
  if (error.empty()) return {true, ""};
  if (mode == NetworkMode::kPrivate) throw std::runtime_error(error);
  return {false, error};
}

}  // namespace shapesense
