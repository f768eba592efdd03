#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

namespace shapesense {

// Groups the images the fake cameras make into frame-sets, so that every
// camera triggered for one set shows the same scene. The capture side
// triggers every camera once per set, all within a few milliseconds; a fake
// camera makes one image per trigger, or one for several when triggers pile
// up while its thread is late (it keeps a single pending-trigger flag).
//
// Assign: each camera counts: its image belongs to the next set it has not
// served, unless newer sets exist, in which case its late image answered the
// newest trigger and joins the newest set. A set is opened by the first
// image of it, at that time (the scene's time). A camera's first image after
// its acquisition started (a fake camera answers it only at its next 100 ms
// poll, merging the triggers sent meanwhile) joins the oldest set opened
// since the acquisition started: the capture side's first trigger to it.
//
// AssignByTrigger, when the time each image's trigger reached its camera is
// known (the rig-sim watches the cameras' trigger registers): an image
// belongs to the newest trigger that came before its own, as the capture
// service's Aravis backend decides from the image's timestamp
// (services/capture/aravis_trigger_matcher.h). Counting goes wrong for good
// once a camera misses one trigger or answers one late by more than a
// period (a loaded machine); times put every image where the client puts it.
// Not thread-safe: the caller holds a lock.
class FrameSetClock {
 public:
  struct Slot {
    int64_t seq = 0;          // frame-set counter, from 0
    int64_t first_utime = 0;  // when the set's first image was asked for
    bool opened = false;      // this image started the set
  };

  explicit FrameSetClock(int num_cameras) : next_(static_cast<size_t>(num_cameras), -1) {}

  // `session_start_utime`: when the camera's acquisition started, for its
  // first image since then; -1 for every later image.
  Slot Assign(int camera, int64_t now_utime, int64_t session_start_utime = -1);
  // `trigger_utime`: when the trigger this image answers reached the camera;
  // the set opened by it starts then. Triggers of one set reach the cameras
  // within a few milliseconds of each other, sets a trigger period apart
  // (the median interval between recent sets).
  Slot AssignByTrigger(int camera, int64_t trigger_utime);

 private:
  struct Opened {
    int64_t seq;
    int64_t first_utime;
  };
  Slot FirstOfSession(int camera, int64_t now_utime, int64_t session_start_utime);
  Slot Open(int64_t now_utime);
  Slot Recent(int64_t seq) const;
  // The median interval between recent sets' first images, µs; 0 while unknown.
  int64_t Period() const;

  // Per camera: the set its next image belongs to (Assign; -1 unknown), the
  // oldest its next image may join (AssignByTrigger).
  std::vector<int64_t> next_;
  std::deque<Opened> recent_;
  int64_t seq_ = -1;
};

}  // namespace shapesense
