#pragma once

// The views the carving service prepared of images still waiting in the
// frame-set assembler, found again by the image's identity when their set
// completes. Identity, not arrival order: a view is used only for the very
// image it was made of.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <vector>

#include "runtime/lcm/frame_set_assembler.h"
#include "runtime/lcm/pipeline_stages.h"
#include "shapesense/image_t.hpp"

namespace shapesense {

// What identifies an image to the assembler: its camera (rig index), its
// trigger, and the camera's frame id and exposure timestamp.
struct ImageIdentity {
  size_t camera = 0;
  int64_t trigger_seq = -1;
  int64_t trigger_utime = 0;
  int64_t frame_id = 0;
  int64_t device_timestamp_ns = 0;
  bool operator==(const ImageIdentity&) const = default;
};
ImageIdentity IdentityOf(size_t camera, const image_t& image);

class PreparedViews {
 public:
  // Holds at most `capacity` views; beyond it the oldest goes. The service
  // keeps its images' fields only (their bytes are read in place), so a set
  // whose view went fails to carve and is counted: the capacity allows for
  // every image the assembler's pending sets can hold, and one set more.
  explicit PreparedViews(size_t capacity);

  // Keeps the view of an image the assembler accepted, replacing any view
  // kept for the same identity (the assembler holds the image accepted last).
  void Keep(const ImageIdentity& image, PreparedView view);

  // The views of a completed set's images (in rig order, as its images),
  // taken out; an image without one gets an empty view (end_utime 0), which
  // CarvingStage::Carve prepares when the image still holds its bytes.
  std::vector<PreparedView> Take(const FrameSet& set);

  size_t size() const { return kept_.size(); }

 private:
  struct Entry {
    ImageIdentity image;
    PreparedView view;
  };
  size_t capacity_;
  std::deque<Entry> kept_;  // oldest first
};

// Views whose buffers wait to be used again: the worker gives back what a
// carving swapped out, the bus thread takes a view per arriving image, and
// the images' buffers (about 1 MB a view) are not allocated and faulted in
// anew for every image. Thread-safe.
class ViewPool {
 public:
  explicit ViewPool(size_t capacity) : capacity_(capacity) {}

  // A view with earlier buffers, or an empty one.
  PreparedView Take();
  // Keeps up to the capacity of `views`, and empties it.
  void Give(std::vector<PreparedView>* views);

 private:
  const size_t capacity_;
  std::mutex mutex_;
  std::vector<PreparedView> free_;
};

}  // namespace shapesense
