#pragma once

// A CAN bus in memory: every frame one endpoint sends reaches every other
// endpoint (as on a wire), in order, each into a bounded receive queue that
// drops its oldest frame when full (as a controller's overrun does). An
// endpoint's link can be cut: its sends then fail as on a bus-off and it
// receives nothing. Thread-safe; endpoints may live on different threads.

#include <cstdint>
#include <memory>
#include <string>

#include "libs/actuation/can_bus.h"

namespace shapesense {

class InMemoryCanNetwork {
 public:
  explicit InMemoryCanNetwork(size_t queue_capacity = 1024);
  ~InMemoryCanNetwork();

  // A new endpoint named `name` ("master", "node 3"); it may outlive the network object.
  std::unique_ptr<CanBus> Attach(const std::string& name);
  // Cuts or restores the link of every endpoint named `name` (also ones attached later).
  void SetLinkUp(const std::string& name, bool up);
  // Frames dropped from full receive queues so far.
  int64_t overruns() const;

  struct State;

 private:
  std::shared_ptr<State> state_;
};

}  // namespace shapesense
