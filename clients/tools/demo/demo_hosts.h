#pragma once

// `shapesense demo --hosts 3`: the closed-loop experiment spread over three
// virtual hosts (runtime/process/virtual_hosts.h), laid out by a rig file as
// a real rig would be (docs/rig.md):
//
//   camera   rig-sim, capture, carving, shape   (images on its local network)
//   control  controller                          ── rig network (ttl=1) ──
//   operator lcm-logger, rig status, the experimenter (this process's bus)
//
// The demo writes the rig file, checks it as `shapesense rig check` would,
// and starts each program on its host with the rig file's environment:
// exactly what `shapesense rig units` puts in the units. The voxel cloud
// stays on the camera host (carving and shape both run there), so only
// compact messages cross the bridge.
#include <atomic>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "runtime/lcm/bus_auth.h"
#include "runtime/process/process_group.h"
#include "runtime/process/virtual_hosts.h"
#include "runtime/rig/rig_file.h"

namespace shapesense {

inline constexpr const char* kCameraHostName = "camera";
inline constexpr const char* kControlHostName = "control";
inline constexpr const char* kOperatorHostName = "operator";

// The rig network of the virtual hosts: its own group, ttl=1 across the
// bridge, receive buffers for bursts of status and shapes.
inline constexpr const char* kDemoRigNetworkUrl =
    "udpm://239.255.77.1:7701?ttl=1&recv_buf_size=4194304";

// The three hosts; the camera host's clock `camera_clock_offset_ms` off
// (test-only, runtime/host_clock.h), with one loopback address per camera.
std::vector<VirtualHostSpec> DemoHostSpecs(double camera_clock_offset_ms, int cameras);

// The demo's rig file (config/rig.yaml's form) naming the hosts, their
// programs and the networks: `local_network` for the images.
std::string DemoRigFileText(const std::vector<std::string>& cameras,
                            const std::string& local_network, const AuthOptions& auth);

// The host of a program of the demo's plan, by its name ("rig-sim-backdrop",
// "capture-background", "controller-closed_loop", ...); throws
// std::invalid_argument for a name the layout does not place.
std::string DemoHostOf(const std::string& program_name);

// Runs `spec` on its host (DemoHostOf) with the rig file's environment.
void PlaceOnDemoHost(const VirtualHosts& hosts, const RigFile& rig, ProgramSpec* spec);

// Every message on a network as one host hears it, counted by channel: what
// crossed the rig network (the demo's proof that no image did). Listens on
// a thread of its own, made in the calling thread's network namespace.
class NetworkCensus {
 public:
  // Throws std::runtime_error when LCM cannot open `url`.
  explicit NetworkCensus(const std::string& url);
  ~NetworkCensus();
  NetworkCensus(const NetworkCensus&) = delete;
  NetworkCensus& operator=(const NetworkCensus&) = delete;

  std::map<std::string, int64_t> Counts() const;

 private:
  void OnMessage(const lcm::ReceiveBuffer* buffer, const std::string& channel);

  lcm::LCM lcm_;
  std::atomic<bool> done_{false};
  mutable std::mutex mutex_;
  std::map<std::string, int64_t> counts_;
  std::thread thread_;
};

}  // namespace shapesense
