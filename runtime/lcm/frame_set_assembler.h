#pragma once

// Groups the images of the rig's cameras into frame-sets. Pure logic: the
// caller passes the time, so the live services (receive time) and replay
// (log time) assemble the same sets from the same stream.
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "shapesense/image_t.hpp"

namespace shapesense {

struct FrameSetAssemblyOptions {
  // Free-running cameras (trigger_seq < 0): images whose trigger times (or,
  // without one, host times) lie within this of a set's first image belong
  // to it, ms.
  double time_tolerance_ms = 2.0;
  // A set still missing images this long after its first image arrived is
  // dropped and counted, ms.
  double timeout_ms = 200.0;
  // Sets waiting for images at once; beyond it the oldest is dropped and
  // counted (bounds memory when a camera is lost).
  int max_pending = 8;
  // Triggered cameras stamping their exposures on one clock (PTP): a set
  // whose exposures lie further apart than this is dropped and counted (its
  // views would not show one shape), ms.
  double max_exposure_spread_ms = 10.0;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("time_tolerance_ms", time_tolerance_ms,
          "free-running cameras: largest spread of one set's image times, ms (0-1000)");
    visit("timeout_ms", timeout_ms, "incomplete set dropped after this, ms (1-60000)");
    visit("max_pending", max_pending, "incomplete sets kept at once (1-1000)");
    visit("max_exposure_spread_ms", max_exposure_spread_ms,
          "triggered sets: largest spread of their exposure timestamps, ms (0.01-1000)");
  }
  std::string Validate() const;
};

// The images of one trigger, one per camera of the rig.
struct FrameSet {
  // The shared trigger sequence, or -1 for a set matched by time.
  int64_t trigger_seq = -1;
  // The earliest trigger (or host) time of its images, µs since epoch.
  int64_t trigger_utime = 0;
  std::vector<image_t> images;         // in rig order
  std::vector<int64_t> receive_utime;  // when each image arrived
  int64_t first_receive_utime = 0;
  int64_t complete_utime = 0;  // when the last image arrived
};

// Identifies a frame-set across services: the carving and shape services
// assemble the same images into the same key.
struct FrameSetKey {
  int64_t trigger_seq = -1;
  int64_t trigger_utime = 0;
  auto operator<=>(const FrameSetKey&) const = default;
};
inline FrameSetKey KeyOf(const FrameSet& set) { return {set.trigger_seq, set.trigger_utime}; }

// When the set's measurement was taken, on this host's clock: each image's
// receive time less its age at publish (header_t.data_age_us), the earliest
// of them. Never the trigger time itself, which is the camera host's clock.
int64_t MeasuredUtime(const FrameSet& set);

enum class AssemblyOutcome {
  kPending,        // joined or started a set that still misses images
  kCompleted,      // completed a set
  kDuplicate,      // its camera already has this very image (same frame id) in that set: ignored
  kConflicting,    // its camera already has another image in the set, or the image gives
                   // the set another trigger time: the set is dropped, never measured
  kSpread,         // completed a set whose exposures lie too far apart: dropped
  kUnknownCamera,  // not a camera of the rig: ignored
  kLate,           // its set was completed or dropped already: ignored
};
const char* AssemblyOutcomeName(AssemblyOutcome outcome);
// Whether the image itself was refused (a duplicate, a conflict, an unknown
// camera, a late image), as opposed to joining, completing or ending a set.
bool IsRejection(AssemblyOutcome outcome);

struct AssemblyResult {
  AssemblyOutcome outcome = AssemblyOutcome::kPending;
  std::optional<FrameSet> completed;  // with kCompleted
};

struct AssemblyCounters {
  int64_t completed = 0;
  int64_t timed_out = 0;    // incomplete sets dropped after the timeout
  int64_t evicted = 0;      // incomplete sets dropped to stay within max_pending
  int64_t conflicting = 0;  // sets dropped because their images disagree on their trigger
  int64_t spread = 0;       // sets dropped because their exposures lie too far apart
  int64_t duplicates = 0;
  int64_t unknown_camera = 0;
  int64_t late = 0;
  int64_t DroppedSets() const { return timed_out + evicted + conflicting + spread; }
  int64_t RejectedImages() const { return duplicates + unknown_camera + late; }
};

// Images with trigger_seq >= 0 form a set when every camera has one with the
// same sequence; images with trigger_seq < 0 (free-running cameras) when
// every camera has one within the time tolerance. Images may arrive in any
// order, also across sets. A set whose images disagree (two different
// images from one camera, or two trigger times for one sequence) is
// dropped and counted: nothing proves which belongs. Holds at most
// max_pending sets.
class FrameSetAssembler {
 public:
  // `cameras`: the rig's camera names, in rig order. Throws
  // std::invalid_argument on no cameras, repeated names or options that fail
  // Validate().
  FrameSetAssembler(std::vector<std::string> cameras, const FrameSetAssemblyOptions& options);

  // Drops the sets that timed out by `now_utime`, then adds the image.
  AssemblyResult Add(image_t image, int64_t now_utime);
  // Drops the sets that timed out by `now_utime`; returns how many.
  int Expire(int64_t now_utime);

  size_t pending() const { return pending_.size(); }
  const AssemblyCounters& counters() const { return counters_; }
  // What the last dropped set was missing, e.g. "frame-set 12: no image from cam1".
  const std::string& last_drop() const { return last_drop_; }
  const std::vector<std::string>& cameras() const { return cameras_; }

 private:
  struct Pending {
    FrameSet set;
    int64_t reference_utime = 0;      // the first image's time: free-running images match it
    int64_t given_trigger_utime = 0;  // the first image's trigger_utime, as it came
    int received = 0;
  };

  int CameraIndex(const std::string& name) const;
  // The pending set the image belongs to, or nullptr.
  Pending* FindSet(const image_t& image, int64_t image_time);
  bool IsRetired(const image_t& image, int64_t image_time) const;
  Pending& StartSet(const image_t& image, int64_t image_time, int64_t now_utime);
  void Retire(const Pending& pending);
  void Drop(const Pending& pending, const char* why);
  // Whether `image` contradicts what `pending` holds (see kConflicting).
  bool Conflicts(const Pending& pending, const image_t& image, size_t slot) const;
  AssemblyResult DropConflicting(Pending* pending);
  // The spread of a complete triggered set's exposure stamps, µs; 0 when
  // some image has none.
  static int64_t ExposureSpread(const FrameSet& set);

  std::vector<std::string> cameras_;
  FrameSetAssemblyOptions options_;
  int64_t tolerance_us_;
  int64_t timeout_us_;
  int64_t max_spread_us_;
  std::deque<Pending> pending_;      // oldest first
  std::deque<FrameSetKey> retired_;  // recently completed or dropped, to recognise late images
  AssemblyCounters counters_;
  std::string last_drop_;
};

}  // namespace shapesense
