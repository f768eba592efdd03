#include "tests/bench/pipeline_listener.h"

#include "runtime/lcm/channels.h"

namespace shapesense::bench {

using std::chrono::milliseconds;

PipelineListener::PipelineListener(const std::string& url) : bus_(url) {
  bus_.Subscribe<shape_t>(channels::kShape, [this](const shape_t& shape, const std::string&,
                                                   int64_t receive) { OnShape(shape, receive); });
  bus_.Subscribe<service_status_t>(
      channels::kStatusPattern,
      [this](const service_status_t& status, const std::string&, int64_t) { OnStatus(status); });
  thread_ = std::thread([this] {
    while (!stop_) {
      // An LCM error must not turn the loop into a spin.
      if (bus_.Handle(20) < 0) std::this_thread::sleep_for(milliseconds(20));
    }
  });
}

PipelineListener::~PipelineListener() {
  stop_ = true;
  thread_.join();
}

std::vector<ShapeSample> PipelineListener::Shapes(int64_t first, int64_t end) const {
  std::lock_guard lock(mutex_);
  std::vector<ShapeSample> out;
  for (auto it = shapes_.lower_bound(first); it != shapes_.end() && it->first < end; ++it) {
    out.push_back(it->second);
  }
  return out;
}

size_t PipelineListener::CountShapes(int64_t first, int64_t end) const {
  std::lock_guard lock(mutex_);
  return static_cast<size_t>(std::distance(shapes_.lower_bound(first), shapes_.lower_bound(end)));
}

std::optional<service_status_t> PipelineListener::Status(const std::string& service) const {
  std::lock_guard lock(mutex_);
  const auto it = statuses_.find(service);
  if (it == statuses_.end()) return std::nullopt;
  return it->second;
}

void PipelineListener::OnShape(const shape_t& shape, int64_t receive_utime) {
  ShapeSample sample{shape.trigger_seq, shape.trigger_utime, receive_utime, shape.valid != 0,
                     shape.stage_times};
  std::lock_guard lock(mutex_);
  shapes_[shape.trigger_seq] = std::move(sample);
}

void PipelineListener::OnStatus(const service_status_t& status) {
  std::lock_guard lock(mutex_);
  statuses_[status.service] = status;
}

bool WaitForStatuses(const PipelineListener& listener, int64_t after_utime, milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto carving = listener.Status("carving");
    const auto shape = listener.Status("shape");
    if (carving && shape && carving->header.utime > after_utime &&
        shape->header.utime > after_utime) {
      return true;
    }
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(milliseconds(10));
  }
}

}  // namespace shapesense::bench
