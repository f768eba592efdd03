#pragma once

// Where each camera's images travel.
//
// An image is ~1 MB: about 16 LCM fragments and 700 Ethernet frames. On
// LCM's UDP multicast every process listening on a group's port receives,
// copies and reassembles every datagram sent to it, whatever the channel; so
// with all channels on one port the shape service, the controller and every
// monitor would pay for each image. Each camera's channel therefore gets its
// own port on the host-local network (lcm_bus.h), its port + 1 + the
// camera's index in the rig (the group and the options stay the network's): only the capture
// service that publishes a camera's images and the processes that use them (the carving service, a
// logger of images) listen there. The kernel sorts datagrams to sockets by
// port, so a process never sees another port's traffic. (A different group
// on the same port would not do: Linux delivers a group's datagrams to every
// socket bound to the port on a host that joined it.) Other providers
// (memq://, in-process) carry the images on the main bus.
#include <memory>
#include <string>
#include <vector>

#include "runtime/lcm/lcm_bus.h"

namespace shapesense {

// The provider URL of camera `camera_index`'s images for a rig on `url`
// (udpm://group:port?options, port 7667 when absent): the same with port +
// 1 + camera_index. Any other provider: `url` itself. Throws
// std::invalid_argument on a udpm URL whose port is not a number or whose
// image ports would pass 65535.
std::string ImageUrl(const std::string& url, size_t camera_index);

// Whether ImageUrl gives each camera a bus of its own on `url`.
bool HasImageBuses(const std::string& url);

// The image buses of a process on `main`: one per camera on main's local
// network when it is udpm, `main` itself otherwise. Opening them is lazy: a process opens only the
// cameras it uses.
class ImageBuses {
 public:
  // `main` must outlive this.
  ImageBuses(LcmBus& main, size_t cameras);

  // Camera k's bus (opened on first use). Throws std::runtime_error when LCM
  // cannot start on it.
  LcmBus& ForCamera(size_t camera_index);
  // The buses opened so far besides `main`: for the process's loop to handle.
  std::vector<LcmBus*> Opened() const;

 private:
  LcmBus& main_;
  std::vector<std::unique_ptr<LcmBus>> own_;  // per camera; empty when on main
};

}  // namespace shapesense
