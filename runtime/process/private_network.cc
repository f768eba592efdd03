#include "runtime/process/private_network.h"

#include <sched.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>

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

}  // namespace shapesense
