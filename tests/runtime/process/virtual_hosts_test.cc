// Virtual hosts (camera, control, operator) inside the test's own private
// network namespace: a program placed on a host sees its name, clock offset
// and address; UDP multicast with ttl=1 crosses the bridge, ttl=0 stays on
// its host; a link taken down lets nothing through until it is up again; the
// link's byte counters follow the traffic. Absence is shown by order, not by
// waiting: a ttl=1 marker sent after the datagrams that must not arrive.
#include "runtime/process/virtual_hosts.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <thread>

#include "tests/support/network_test.h"

namespace shapesense {
namespace {

using std::chrono::milliseconds;
using std::chrono::steady_clock;

constexpr const char* kGroup = "239.255.79.1";
constexpr uint16_t kPort = 7901;
constexpr milliseconds kPatience(5000);  // every wait's bound

// A UDP socket opened inside a host's network namespace (by a thread that
// enters it: the socket stays the host's whichever thread uses it).
class Socket {
 public:
  Socket(const VirtualHosts& hosts, const std::string& host) {
    std::string error;
    std::thread opener([&] {
      try {
        hosts.EnterFromThisThread(host);
        fd_ = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
      } catch (const std::exception& e) {
        error = e.what();
      }
    });
    opener.join();
    if (fd_ < 0) throw std::runtime_error("no socket on " + host + ": " + error);
  }
  ~Socket() { close(fd_); }
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
};

sockaddr_in GroupAddress() {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(kPort);
  inet_pton(AF_INET, kGroup, &address.sin_addr);
  return address;
}

// Sends datagrams to the group with a given ttl (0: host-local).
class Sender {
 public:
  Sender(const VirtualHosts& hosts, const std::string& host, int ttl) : socket_(hosts, host) {
    const unsigned char value = static_cast<unsigned char>(ttl);
    if (setsockopt(socket_.fd(), IPPROTO_IP, IP_MULTICAST_TTL, &value, sizeof(value)) != 0) {
      throw std::runtime_error("IP_MULTICAST_TTL refused");
    }
  }
  void Send(const std::string& text) const {
    const sockaddr_in group = GroupAddress();
    const auto* address = reinterpret_cast<const sockaddr*>(&group);
    ASSERT_EQ(sendto(socket_.fd(), text.data(), text.size(), 0, address, sizeof(group)),
              static_cast<ssize_t>(text.size()))
        << text;
  }

 private:
  Socket socket_;
};

// A member of the group on a host, keeping every datagram it receives.
class Receiver {
 public:
  Receiver(const VirtualHosts& hosts, const std::string& host) : socket_(hosts, host) {
    const int yes = 1;
    setsockopt(socket_.fd(), SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
    sockaddr_in any{};
    any.sin_family = AF_INET;
    any.sin_port = htons(kPort);
    if (bind(socket_.fd(), reinterpret_cast<const sockaddr*>(&any), sizeof(any)) != 0) {
      throw std::runtime_error("bind failed on " + host);
    }
    ip_mreq membership{};  // the interface the route to the group names: rig0
    inet_pton(AF_INET, kGroup, &membership.imr_multiaddr);
    if (setsockopt(socket_.fd(), IPPROTO_IP, IP_ADD_MEMBERSHIP, &membership, sizeof(membership)) !=
        0) {
      throw std::runtime_error("IP_ADD_MEMBERSHIP failed on " + host);
    }
  }

  // Reads until a datagram `text` has come (true) or `timeout` passed.
  bool WaitFor(const std::string& text, milliseconds timeout) {
    const auto deadline = steady_clock::now() + timeout;
    while (std::find(received_.begin(), received_.end(), text) == received_.end()) {
      const auto left = std::chrono::duration_cast<milliseconds>(deadline - steady_clock::now());
      if (left.count() <= 0) return false;
      ReadOne(static_cast<int>(left.count()));
    }
    return true;
  }
  // How many datagrams received so far start with `prefix`.
  int CountOf(const std::string& prefix) const {
    return static_cast<int>(
        std::count_if(received_.begin(), received_.end(),
                      [&](const auto& text) { return text.starts_with(prefix); }));
  }

 private:
  void ReadOne(int timeout_ms) {
    pollfd ready{socket_.fd(), POLLIN, 0};
    if (poll(&ready, 1, timeout_ms) <= 0) return;
    char buffer[2048];
    const ssize_t n = recv(socket_.fd(), buffer, sizeof(buffer), 0);
    if (n >= 0) received_.emplace_back(buffer, static_cast<size_t>(n));
  }

  Socket socket_;
  std::vector<std::string> received_;
};

// Sends `text` every 50 ms until `receiver` has it (a link just brought up
// may need a moment); false when it never arrives within kPatience.
bool SendUntilReceived(const Sender& sender, Receiver& receiver, const std::string& text) {
  const auto deadline = steady_clock::now() + kPatience;
  while (steady_clock::now() < deadline) {
    sender.Send(text);
    if (receiver.WaitFor(text, milliseconds(50))) return true;
  }
  return false;
}

// Runs `script` with sh under `options`; its output once it ended (bounded).
std::string RunSh(const std::string& script, const ChildOptions& options) {
  ChildOptions merged = options;
  merged.capture_stderr = true;
  ChildProcess child({"/bin/sh", "-c", script}, merged);
  const auto deadline = steady_clock::now() + kPatience;
  while (!child.ExitStatus() && steady_clock::now() < deadline) {
    child.ReadAvailable();
    std::this_thread::sleep_for(milliseconds(5));
  }
  child.ReadAvailable();  // what it wrote just before it ended
  child.Stop();
  return child.output();
}

class VirtualHostsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(nettest::PrivateNetworkError(), "");
    hosts_ = std::make_unique<VirtualHosts>(
        std::vector<VirtualHostSpec>{{"camera", -12.5, 2}, {"control", 0, 0}, {"operator", 40, 0}});
  }

  std::unique_ptr<VirtualHosts> hosts_;
};

TEST_F(VirtualHostsTest, AddressesAndNamespacesByHost) {
  EXPECT_EQ(hosts_->Address("camera"), "10.77.0.1");
  EXPECT_EQ(hosts_->Address("control"), "10.77.0.2");
  EXPECT_EQ(hosts_->hosts().size(), 3u);
  EXPECT_NE(hosts_->NamespaceFd("camera"), hosts_->NamespaceFd("control"));
  try {
    hosts_->NamespaceFd("nowhere");
    FAIL() << "an unknown host has a namespace";
  } catch (const std::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("nowhere"), std::string::npos) << e.what();
  }
}

TEST_F(VirtualHostsTest, AProgramOnAHostSeesItsNameOffsetAndAddresses) {
  ChildOptions options;
  options.environment = {{"SHAPESENSE_LOCAL_LCM_URL", "udpm://239.255.76.67:7667?ttl=0"}};
  hosts_->PlaceOn("camera", &options);
  const std::string output = RunSh(
      "hostname; echo $SHAPESENSE_TEST_CLOCK_OFFSET_MS; echo $SHAPESENSE_LOCAL_LCM_URL; "
      "ip -4 -o addr show dev rig0; ip -4 -o addr show dev lo",
      options);
  EXPECT_EQ(output.rfind("camera\n-12.5\nudpm://239.255.76.67:7667?ttl=0\n", 0), 0u) << output;
  EXPECT_NE(output.find("10.77.0.1/24"), std::string::npos) << output;
  EXPECT_NE(output.find("127.0.0.3/8"), std::string::npos) << output;
  EXPECT_EQ(output.find("10.77.0.2"), std::string::npos) << output;
  char own_name[256] = {};
  gethostname(own_name, sizeof(own_name) - 1);
  EXPECT_NE(std::string(own_name), "camera") << "the test's own host name is untouched";
}

TEST_F(VirtualHostsTest, AProcessGroupRunsAProgramOnItsHost) {
  const auto logs = std::filesystem::path(::testing::TempDir()) /
                    ("virtual_hosts_test_" + std::to_string(getpid()));
  std::atomic<bool> stop{false};
  ProcessGroup group(logs, stop, {[](int) {}, [](const std::string&) { return false; }});
  ProgramSpec program;
  program.name = "on-operator";
  program.argv = {"/bin/sh", "-c",
                  "test \"$(hostname)\" = operator && "
                  "test \"$SHAPESENSE_TEST_CLOCK_OFFSET_MS\" = 40 && "
                  "ip -4 -o addr show dev rig0 | grep -q 10.77.0.3/24"};
  program.runs_to_end = true;
  hosts_->PlaceOn("operator", &program);
  EXPECT_TRUE(group.Start(program, std::chrono::seconds(10)));
  std::filesystem::remove_all(logs);
}

TEST_F(VirtualHostsTest, RigMulticastCrossesTheBridge) {
  Receiver control(*hosts_, "control");
  Receiver operator_host(*hosts_, "operator");
  const Sender camera(*hosts_, "camera", 1);
  ASSERT_TRUE(SendUntilReceived(camera, control, "hello"));
  EXPECT_TRUE(operator_host.WaitFor("hello", kPatience));
}

TEST_F(VirtualHostsTest, HostLocalMulticastStaysOnItsHost) {
  Receiver camera_receiver(*hosts_, "camera");
  Receiver control(*hosts_, "control");
  const Sender rig(*hosts_, "camera", 1);
  const Sender local(*hosts_, "camera", 0);
  ASSERT_TRUE(SendUntilReceived(rig, control, "first"));
  for (int i = 0; i < 10; ++i) local.Send("local-" + std::to_string(i));
  rig.Send("marker");  // behind the local ones, had they left the host
  ASSERT_TRUE(control.WaitFor("marker", kPatience));
  EXPECT_EQ(control.CountOf("local-"), 0);
  ASSERT_TRUE(camera_receiver.WaitFor("local-9", kPatience));
  EXPECT_EQ(camera_receiver.CountOf("local-"), 10);
}

TEST_F(VirtualHostsTest, APulledLinkLetsNothingThroughUntilItIsBack) {
  Receiver control(*hosts_, "control");
  Receiver operator_host(*hosts_, "operator");
  const Sender camera(*hosts_, "camera", 1);
  ASSERT_TRUE(SendUntilReceived(camera, control, "before"));

  hosts_->SetLink("control", false);
  for (int i = 0; i < 10; ++i) camera.Send("lost-" + std::to_string(i));
  camera.Send("lost-end");
  // The bridge floods each datagram to every port at once: once the operator
  // has them all, the control's copies were dropped, not held back.
  ASSERT_TRUE(operator_host.WaitFor("lost-end", kPatience));
  EXPECT_EQ(operator_host.CountOf("lost-"), 11);
  ChildOptions on_control;
  hosts_->PlaceOn("control", &on_control);
  EXPECT_NE(RunSh("ip -4 -o addr show dev rig0", on_control).find("10.77.0.2/24"),
            std::string::npos)
      << "the host keeps its address while its link is down";

  hosts_->SetLink("control", true);
  ASSERT_TRUE(SendUntilReceived(camera, control, "after"));
  EXPECT_EQ(control.CountOf("lost-"), 0);
}

TEST_F(VirtualHostsTest, ByteCountersFollowTheTraffic) {
  Receiver control(*hosts_, "control");
  const Sender camera(*hosts_, "camera", 1);
  ASSERT_TRUE(SendUntilReceived(camera, control, "start"));
  const VirtualHosts::LinkBytes received_before = hosts_->Bytes("control");
  const VirtualHosts::LinkBytes sent_before = hosts_->Bytes("camera");
  const std::string payload(1000, 'x');
  for (int i = 0; i < 20; ++i) camera.Send("data-" + std::to_string(i) + payload);
  ASSERT_TRUE(control.WaitFor("data-19" + payload, kPatience));
  EXPECT_EQ(control.CountOf("data-"), 20);
  EXPECT_GE(hosts_->Bytes("control").received - received_before.received, 20u * 1000u);
  EXPECT_GE(hosts_->Bytes("camera").sent - sent_before.sent, 20u * 1000u);
}

using Specs = std::vector<VirtualHostSpec>;

TEST_F(VirtualHostsTest, AFailedStepIsNamedAndTheNamesFreedAtTheEnd) {
  try {
    const VirtualHosts second(Specs{{"spare"}});
    FAIL() << "a second bridge of the same name was made";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("make the bridge"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("exists"), std::string::npos) << e.what();
  }
  EXPECT_THROW(VirtualHosts{Specs({{"a"}, {"a"}})}, std::invalid_argument);
  hosts_.reset();
  EXPECT_NO_THROW(VirtualHosts{Specs{{"again"}}}) << "the bridge and the veth names are free again";
}

}  // namespace
}  // namespace shapesense
