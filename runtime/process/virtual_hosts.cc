#include "runtime/process/virtual_hosts.h"

#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "runtime/process/private_network.h"

namespace shapesense {
namespace {

// runtime/host_clock.h's kTestClockOffsetVariable, written out: this library
// does not link shapesense::host_clock for one name.
constexpr const char* kClockOffsetVariable = "SHAPESENSE_TEST_CLOCK_OFFSET_MS";

// Generous: an `ip` command takes milliseconds, but the machine is shared.
constexpr std::chrono::seconds kIpTimeout(20);

std::string PeerName(size_t index) { return "v-" + std::to_string(index); }

std::string Joined(const std::vector<std::string>& words) {
  std::string text;
  for (const std::string& word : words) text += (text.empty() ? "" : " ") + word;
  return text;
}

std::string ErrnoText(const std::string& what) { return what + ": " + std::strerror(errno); }

// The calling thread's network namespace, as an fd; -1 and `error` set when
// it cannot be opened.
int OpenThisThreadsNamespace(std::string* error) {
  const int fd = open("/proc/thread-self/ns/net", O_RDONLY | O_CLOEXEC);
  if (fd < 0) *error = ErrnoText("open(/proc/thread-self/ns/net)");
  return fd;
}

// Runs `work` on a thread of its own (which may change its namespaces
// without touching the caller's) and waits for it.
template <class Work>
void OnItsOwnThread(Work work) {
  std::thread thread(work);
  thread.join();
}

// A new network namespace, made by a thread that leaves the caller's
// untouched; it lives as long as the fd returned.
int MakeNetworkNamespace() {
  int fd = -1;
  std::string error;
  OnItsOwnThread([&] {
    if (unshare(CLONE_NEWNET) != 0) {
      error = ErrnoText("unshare(CLONE_NEWNET)");
      return;
    }
    fd = OpenThisThreadsNamespace(&error);
  });
  if (fd < 0) throw std::runtime_error(error);
  return fd;
}

// Waits (bounded) for a short-lived child to end; its status, -1 when it did
// not end in time (it is killed).
int WaitForEnd(ChildProcess& child, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    child.ReadAvailable();
    if (const std::optional<int> status = child.ExitStatus()) {
      child.ReadAvailable();
      return *status;
    }
    if (std::chrono::steady_clock::now() > deadline) return child.Stop(std::chrono::seconds(1));
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

// rig0's byte counters in /proc/<tid>/net/dev text: the receive bytes are the
// first number after "rig0:", the transmit bytes the ninth.
VirtualHosts::LinkBytes ParseLinkBytes(const std::string& net_dev, const std::string& interface) {
  std::istringstream lines(net_dev);
  const std::string label = interface + ":";
  for (std::string line; std::getline(lines, line);) {
    const size_t start = line.find_first_not_of(' ');
    if (start == std::string::npos || line.compare(start, label.size(), label) != 0) continue;
    std::istringstream fields(line.substr(start + label.size()));
    std::vector<uint64_t> numbers;
    for (uint64_t number = 0; fields >> number;) numbers.push_back(number);
    if (numbers.size() < 9) break;
    return {numbers[0], numbers[8]};
  }
  throw std::runtime_error("no counters for " + interface + " in /proc/thread-self/net/dev");
}

void CheckNames(const std::vector<VirtualHostSpec>& hosts) {
  std::set<std::string> names;
  for (const VirtualHostSpec& host : hosts) {
    if (host.name.empty()) throw std::invalid_argument("VirtualHosts: a host without a name");
    if (!names.insert(host.name).second) {
      throw std::invalid_argument("VirtualHosts: host '" + host.name + "' given twice");
    }
  }
  // 10.77.0.<1 + index>, 255 being the broadcast address.
  if (hosts.size() > 254) throw std::invalid_argument("VirtualHosts: more than 254 hosts");
}

}  // namespace

VirtualHosts::VirtualHosts(const std::vector<VirtualHostSpec>& hosts) : hosts_(hosts) {
  CheckNames(hosts_);
  ip_ = FindOnPath("ip").string();
  if (ip_.empty()) {
    throw std::runtime_error("VirtualHosts: the `ip` tool (Debian package iproute2) is missing");
  }
  std::string error;
  home_ = OpenThisThreadsNamespace(&error);
  if (home_ < 0) throw std::runtime_error("VirtualHosts: " + error);
  try {
    Build();
  } catch (...) {
    TearDown();
    throw;
  }
}

VirtualHosts::~VirtualHosts() { TearDown(); }

void VirtualHosts::Build() {
  // No IGMP snooping: the bridge floods multicast to every port like a plain
  // switch, so that delivery does not hang on membership reports it saw.
  Ip(home_, {"link", "add", kBridge, "type", "bridge", "mcast_snooping", "0"}, "make the bridge");
  bridge_made_ = true;
  Ip(home_, {"link", "set", kBridge, "up"}, "bring the bridge up");
  for (size_t index = 0; index < hosts_.size(); ++index) AddHost(index);
}

void VirtualHosts::AddHost(size_t index) {
  const VirtualHostSpec& host = hosts_[index];
  const std::string step = "host '" + host.name + "': ";
  try {
    namespaces_.push_back(MakeNetworkNamespace());
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("VirtualHosts: " + step + "make its network namespace: " + e.what());
  }
  const int fd = namespaces_.back();
  // The host's end goes straight into its namespace, named by our open fd.
  const std::string host_namespace =
      "/proc/" + std::to_string(getpid()) + "/fd/" + std::to_string(fd);
  Ip(home_,
     {"link", "add", PeerName(index), "type", "veth", "peer", "name", kInterface, "netns",
      host_namespace},
     step + "make its veth pair");
  Ip(home_, {"link", "set", PeerName(index), "master", kBridge, "up"}, step + "join the bridge");
  Ip(fd, {"link", "set", "lo", "up", "multicast", "on"}, step + "bring loopback up");
  for (int i = 1; i <= host.loopback_addresses; ++i) {
    Ip(fd, {"addr", "add", LoopbackAddress(i) + "/8", "dev", "lo"},
       step + "add a loopback address");
  }
  Ip(fd, {"addr", "add", Address(host.name) + "/24", "dev", kInterface}, step + "address rig0");
  Ip(fd, {"link", "set", kInterface, "up"}, step + "bring rig0 up");
  Ip(fd, {"route", "add", "224.0.0.0/4", "dev", kInterface}, step + "route multicast to rig0");
}

void VirtualHosts::TearDown() noexcept {
  for (size_t index = 0; index < namespaces_.size(); ++index) {
    try {  // deleting one end deletes the pair, even while programs use the host
      Ip(home_, {"link", "delete", PeerName(index)}, "delete a veth pair");
    } catch (...) {  // NOLINT(bugprone-empty-catch): it may not have been made; nothing to do
    }
    close(namespaces_[index]);
  }
  namespaces_.clear();
  if (bridge_made_) {
    try {
      Ip(home_, {"link", "delete", kBridge}, "delete the bridge");
    } catch (...) {  // NOLINT(bugprone-empty-catch): a destructor cannot report it
    }
    bridge_made_ = false;
  }
  if (home_ >= 0) close(home_);
  home_ = -1;
}

void VirtualHosts::Ip(int namespace_fd, const std::vector<std::string>& args,
                      const std::string& step) const {
  std::vector<std::string> argv{ip_};
  argv.insert(argv.end(), args.begin(), args.end());
  ChildOptions options;
  options.capture_stderr = true;
  options.network_namespace = namespace_fd;
  std::unique_ptr<ChildProcess> child;
  try {
    child = std::make_unique<ChildProcess>(argv, options);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("VirtualHosts: " + step + ": " + e.what());
  }
  const int status = WaitForEnd(*child, kIpTimeout);
  if (status == 0) return;
  std::string output = child->output();
  while (!output.empty() && output.back() == '\n') output.pop_back();
  throw std::runtime_error("VirtualHosts: " + step + ": '" + Joined(argv) + "' " +
                           DescribeExitStatus(status) + (output.empty() ? "" : ": " + output));
}

size_t VirtualHosts::IndexOf(const std::string& host) const {
  const auto found = std::find_if(hosts_.begin(), hosts_.end(),
                                  [&](const VirtualHostSpec& spec) { return spec.name == host; });
  if (found == hosts_.end()) throw std::out_of_range("VirtualHosts: no host '" + host + "'");
  return static_cast<size_t>(found - hosts_.begin());
}

int VirtualHosts::NamespaceFd(const std::string& host) const {
  return namespaces_.at(IndexOf(host));
}

std::string VirtualHosts::Address(const std::string& host) const {
  return "10.77.0." + std::to_string(1 + IndexOf(host));
}

void VirtualHosts::EnterFromThisThread(const std::string& host) const {
  if (setns(NamespaceFd(host), CLONE_NEWNET) != 0) {
    throw std::runtime_error("VirtualHosts: " + ErrnoText("setns() into host '" + host + "'"));
  }
}

void VirtualHosts::SetLink(const std::string& host, bool up) const {
  Ip(home_, {"link", "set", PeerName(IndexOf(host)), up ? "up" : "down"},
     "host '" + host + "': take its link " + (up ? "up" : "down"));
}

// /proc/thread-self/net shows the namespace of the thread reading it: a
// thread of our own enters the host's, without sysfs mounted for it.
VirtualHosts::LinkBytes VirtualHosts::Bytes(const std::string& host) const {
  const int fd = NamespaceFd(host);
  std::string net_dev;
  std::string error;
  OnItsOwnThread([&] {
    if (setns(fd, CLONE_NEWNET) != 0) {
      error = ErrnoText("setns()");
      return;
    }
    std::ifstream file("/proc/thread-self/net/dev");
    std::ostringstream text;
    text << file.rdbuf();
    net_dev = text.str();
  });
  if (!error.empty()) throw std::runtime_error("VirtualHosts: bytes of '" + host + "': " + error);
  return ParseLinkBytes(net_dev, kInterface);
}

namespace {

// The shortest text that reads back as `value` ("-2.5", "0").
std::string NumberText(double value) {
  char text[64];
  const auto result = std::to_chars(std::begin(text), std::end(text), value);
  return std::string(text, result.ptr);
}

void SetVariable(std::vector<std::pair<std::string, std::string>>* environment,
                 const std::string& name, const std::string& value) {
  std::erase_if(*environment, [&](const auto& variable) { return variable.first == name; });
  environment->emplace_back(name, value);
}

}  // namespace

void VirtualHosts::PlaceOn(const std::string& host, ProgramSpec* spec) const {
  spec->network_namespace = NamespaceFd(host);
  spec->host_name = host;
  SetVariable(&spec->environment, kClockOffsetVariable,
              NumberText(hosts_[IndexOf(host)].clock_offset_ms));
}

void VirtualHosts::PlaceOn(const std::string& host, ChildOptions* options) const {
  options->network_namespace = NamespaceFd(host);
  options->host_name = host;
  SetVariable(&options->environment, kClockOffsetVariable,
              NumberText(hosts_[IndexOf(host)].clock_offset_ms));
}

}  // namespace shapesense
