#include "services/carving/prepared_views.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace shapesense {

ImageIdentity IdentityOf(size_t camera, const image_t& image) {
  return {camera, image.trigger_seq, image.trigger_utime, image.frame_id,
          image.device_timestamp_ns};
}

PreparedViews::PreparedViews(size_t capacity) : capacity_(capacity) {
  if (capacity == 0) throw std::invalid_argument("prepared views: capacity must be positive");
}

void PreparedViews::Keep(const ImageIdentity& image, PreparedView view) {
  std::erase_if(kept_, [&](const Entry& entry) { return entry.image == image; });
  if (kept_.size() == capacity_) kept_.pop_front();
  kept_.push_back({image, std::move(view)});
}

std::vector<PreparedView> PreparedViews::Take(const FrameSet& set) {
  std::vector<PreparedView> views(set.images.size());
  for (size_t k = 0; k < set.images.size(); ++k) {
    const ImageIdentity image = IdentityOf(k, set.images[k]);
    const auto it = std::find_if(kept_.begin(), kept_.end(),
                                 [&](const Entry& entry) { return entry.image == image; });
    if (it == kept_.end()) continue;
    views[k] = std::move(it->view);
    kept_.erase(it);
  }
  return views;
}

PreparedView ViewPool::Take() {
  const std::lock_guard lock(mutex_);
  if (free_.empty()) return {};
  PreparedView view = std::move(free_.back());
  free_.pop_back();
  return view;
}

void ViewPool::Give(std::vector<PreparedView>* views) {
  {
    const std::lock_guard lock(mutex_);
    for (PreparedView& view : *views) {
      if (free_.size() == capacity_) break;
      free_.push_back(std::move(view));
    }
  }
  views->clear();  // what did not fit is freed here, outside the lock
}

}  // namespace shapesense
