#pragma once

// Virtual hosts for the multi-host tests and the demo: the rig's hosts
// (camera, control, operator) on one machine, each a Linux network namespace
// joined by a veth pair to a bridge, the "switch", with an address of its
// own. The rig network (LCM UDP multicast, ttl=1) crosses the bridge; the
// host-local one (ttl=0) stays on its host, as on a real rig. Programs run on
// a host (PlaceOn) see its network, its host name and its clock offset.
//
// Made from the caller's own network namespace (a private one: the bridge and
// the veth peers get fixed names there) and needs CAP_NET_ADMIN and
// CAP_SYS_ADMIN in it (root, or a test binary's user namespace). The hosts'
// namespaces have no name under /run/netns: nothing leaks machine-wide, and
// parallel runs do not collide.

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/process/child_process.h"
#include "runtime/process/process_group.h"

namespace shapesense {

struct VirtualHostSpec {
  std::string name;  // also the host name its programs see
  double clock_offset_ms = 0;
  // Extra loopback addresses 127.0.0.2 ... 127.0.0.(1 + n), for fake GigE
  // cameras (one binds to an address an interface has).
  int loopback_addresses = 0;
};

class VirtualHosts {
 public:
  static constexpr const char* kInterface = "rig0";  // every host's rig interface
  static constexpr const char* kBridge = "rigbr0";   // in the caller's namespace

  // Makes the bridge (up) and, per host (index i), a network namespace with
  // loopback up (multicast on, its extra addresses) and `rig0`, a veth whose
  // peer `v-<i>` is on the bridge, with address 10.77.0.<1 + i>/24, a route
  // for 224.0.0.0/4 (the rig network's multicast), up. Throws
  // std::invalid_argument for names that are empty or repeated, and
  // std::runtime_error naming the step that failed (with `ip`'s message);
  // what was made is then undone. Best called before the process starts
  // threads (each `ip` command is a fork).
  explicit VirtualHosts(const std::vector<VirtualHostSpec>& hosts);
  // Deletes the veth pairs and the bridge and closes the namespaces (each
  // vanishes once no program placed on it still runs).
  ~VirtualHosts();
  VirtualHosts(const VirtualHosts&) = delete;
  VirtualHosts& operator=(const VirtualHosts&) = delete;

  const std::vector<VirtualHostSpec>& hosts() const { return hosts_; }
  // The host's network namespace, an fd (kept open until destruction).
  // Throws std::out_of_range naming an unknown host, as every call taking one.
  int NamespaceFd(const std::string& host) const;
  // Its address on the rig network: "10.77.0.2".
  std::string Address(const std::string& host) const;

  // Moves the calling thread into the host's network namespace (e.g. the
  // demo's own LCM bus on the operator host); sockets it opens from then on
  // are the host's. Throws std::runtime_error when setns() fails.
  void EnterFromThisThread(const std::string& host) const;

  // Takes the host's link down or up at the bridge side (a cable pulled at
  // the switch): the host keeps its address and routes, but nothing crosses.
  void SetLink(const std::string& host, bool up) const;

  // Bytes received and sent on the host's rig0 so far.
  struct LinkBytes {
    uint64_t received = 0;
    uint64_t sent = 0;
  };
  LinkBytes Bytes(const std::string& host) const;

  // Runs a program on the host: its network namespace, its host name and
  // SHAPESENSE_TEST_CLOCK_OFFSET_MS (runtime/host_clock.h) set to its clock
  // offset; other variables in `environment` are kept.
  void PlaceOn(const std::string& host, ProgramSpec* spec) const;
  void PlaceOn(const std::string& host, ChildOptions* options) const;

 private:
  size_t IndexOf(const std::string& host) const;
  void Build();
  void AddHost(size_t index);
  void TearDown() noexcept;
  // Runs `ip <args>` in the namespace `namespace_fd`; throws naming `step`.
  void Ip(int namespace_fd, const std::vector<std::string>& args, const std::string& step) const;

  std::vector<VirtualHostSpec> hosts_;
  std::string ip_;               // the `ip` program (iproute2)
  int home_ = -1;                // the caller's network namespace, where the bridge is
  std::vector<int> namespaces_;  // one per host made so far
  bool bridge_made_ = false;
};

}  // namespace shapesense
