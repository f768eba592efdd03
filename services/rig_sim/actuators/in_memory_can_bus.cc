#include "services/rig_sim/actuators/in_memory_can_bus.h"

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <set>
#include <vector>

namespace shapesense {

namespace {

struct Endpoint {
  std::string name;
  std::deque<CanFrame> queue;
  std::condition_variable ready;
};

}  // namespace

struct InMemoryCanNetwork::State {
  std::mutex mutex;
  size_t capacity = 1024;
  std::vector<Endpoint*> endpoints;
  std::set<std::string> cut;
  int64_t overruns = 0;

  bool IsCut(const std::string& name) const { return cut.contains(name); }
};

namespace {

class InMemoryCanBus : public CanBus {
 public:
  InMemoryCanBus(std::shared_ptr<InMemoryCanNetwork::State> state, const std::string& name)
      : state_(std::move(state)) {
    endpoint_.name = name;
    std::lock_guard lock(state_->mutex);
    state_->endpoints.push_back(&endpoint_);
  }

  ~InMemoryCanBus() override {
    std::lock_guard lock(state_->mutex);
    std::erase(state_->endpoints, &endpoint_);
  }

  std::string name() const override { return "memory:" + endpoint_.name; }

  void Send(const CanFrame& frame) override {
    std::lock_guard lock(state_->mutex);
    if (state_->IsCut(endpoint_.name)) throw LinkDown();
    for (Endpoint* other : state_->endpoints) {
      if (other == &endpoint_ || state_->IsCut(other->name)) continue;
      if (other->queue.size() >= state_->capacity) {
        other->queue.pop_front();
        ++state_->overruns;
      }
      other->queue.push_back(frame);
      other->ready.notify_one();
    }
  }

  std::optional<CanFrame> Receive(std::chrono::microseconds timeout) override {
    std::unique_lock lock(state_->mutex);
    endpoint_.ready.wait_for(
        lock, timeout, [&] { return !endpoint_.queue.empty() || state_->IsCut(endpoint_.name); });
    if (state_->IsCut(endpoint_.name)) throw LinkDown();
    if (endpoint_.queue.empty()) return std::nullopt;
    const CanFrame frame = endpoint_.queue.front();
    endpoint_.queue.pop_front();
    return frame;
  }

 private:
  CanBusError LinkDown() const {
    return CanBusError(name() + ": link down (no other node acknowledges: bus-off)");
  }

  std::shared_ptr<InMemoryCanNetwork::State> state_;
  Endpoint endpoint_;
};

}  // namespace

InMemoryCanNetwork::InMemoryCanNetwork(size_t queue_capacity) : state_(std::make_shared<State>()) {
  state_->capacity = std::max<size_t>(1, queue_capacity);
}

InMemoryCanNetwork::~InMemoryCanNetwork() = default;

std::unique_ptr<CanBus> InMemoryCanNetwork::Attach(const std::string& name) {
  return std::make_unique<InMemoryCanBus>(state_, name);
}

void InMemoryCanNetwork::SetLinkUp(const std::string& name, bool up) {
  std::lock_guard lock(state_->mutex);
  if (up) {
    state_->cut.erase(name);
    return;
  }
  state_->cut.insert(name);
  for (Endpoint* endpoint : state_->endpoints) {
    if (endpoint->name != name) continue;
    endpoint->queue.clear();  // what the cable never delivered
    endpoint->ready.notify_all();
  }
}

int64_t InMemoryCanNetwork::overruns() const {
  std::lock_guard lock(state_->mutex);
  return state_->overruns;
}

}  // namespace shapesense
