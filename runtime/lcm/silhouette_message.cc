#include "runtime/lcm/silhouette_message.h"

namespace shapesense {
namespace {

// A run list on the wire: three parallel arrays.
template <class Vector>
struct WireRuns {
  Vector& row;
  Vector& begin;
  Vector& end;
};
using WriteRuns = WireRuns<std::vector<int16_t>>;
using ReadRuns = WireRuns<const std::vector<int16_t>>;

int32_t ToWire(const std::vector<RowRun>& runs, const WriteRuns& wire) {
  for (std::vector<int16_t>* v : {&wire.row, &wire.begin, &wire.end}) v->resize(runs.size());
  for (size_t i = 0; i < runs.size(); ++i) {
    wire.row[i] = static_cast<int16_t>(runs[i].y);
    wire.begin[i] = static_cast<int16_t>(runs[i].x0);
    wire.end[i] = static_cast<int16_t>(runs[i].x1);
  }
  return static_cast<int32_t>(runs.size());
}

// "" or why the arrays do not hold `count` runs.
std::string FromWire(int32_t count, const ReadRuns& wire, const std::string& what,
                     std::vector<RowRun>* runs) {
  const auto n = static_cast<size_t>(count);
  if (count < 0 || wire.row.size() != n || wire.begin.size() != n || wire.end.size() != n) {
    return what + ": expected " + std::to_string(count) + " runs in each of row, begin and end";
  }
  runs->resize(n);
  for (size_t i = 0; i < n; ++i) (*runs)[i] = {wire.row[i], wire.begin[i], wire.end[i]};
  return {};
}

std::string ViewFromMessage(const silhouette_view_t& view, const Camera& camera,
                            CompactSilhouette* compact) {
  if (view.camera != camera.name) {
    return "expected camera '" + camera.name + "', got '" + view.camera + "'";
  }
  if (view.width != camera.width || view.height != camera.height) {
    return camera.name + ": expected " + std::to_string(camera.width) + "x" +
           std::to_string(camera.height) + " (the rig's), got " + std::to_string(view.width) + "x" +
           std::to_string(view.height);
  }
  compact->width = view.width;
  compact->height = view.height;
  for (const std::string& error :
       {FromWire(view.num_mask_runs, ReadRuns{view.mask_row, view.mask_begin, view.mask_end},
                 "mask", &compact->mask),
        FromWire(view.num_tape_runs, ReadRuns{view.tape_row, view.tape_begin, view.tape_end},
                 "tape", &compact->markers),
        FromWire(view.num_band_runs, ReadRuns{view.band_row, view.band_begin, view.band_end},
                 "edge band", &compact->band)}) {
    if (!error.empty()) return camera.name + ": " + error;
  }
  if (view.num_band_values < 0 ||
      static_cast<size_t>(view.num_band_values) != view.band_difference.size()) {
    return camera.name + ": num_band_values does not match band_difference";
  }
  compact->band_difference = view.band_difference;
  if (std::string error = Validate(*compact); !error.empty()) return camera.name + ": " + error;
  return {};
}

}  // namespace

void SilhouettesToMessage(const Rig& rig, const SilhouetteSet& set, silhouettes_t* message) {
  const std::vector<CompactSilhouette>& compact = set.views;
  message->trigger_seq = set.trigger_seq;
  message->trigger_utime = set.trigger_utime;
  message->views.resize(compact.size());
  message->num_views = static_cast<int32_t>(compact.size());
  for (size_t k = 0; k < compact.size(); ++k) {
    silhouette_view_t& view = message->views[k];
    view.camera = rig.cameras[k].name;
    view.width = compact[k].width;
    view.height = compact[k].height;
    view.num_mask_runs =
        ToWire(compact[k].mask, WriteRuns{view.mask_row, view.mask_begin, view.mask_end});
    view.num_tape_runs =
        ToWire(compact[k].markers, WriteRuns{view.tape_row, view.tape_begin, view.tape_end});
    view.num_band_runs =
        ToWire(compact[k].band, WriteRuns{view.band_row, view.band_begin, view.band_end});
    view.band_difference = compact[k].band_difference;
    view.num_band_values = static_cast<int32_t>(view.band_difference.size());
  }
}

std::string SilhouettesFromMessage(const silhouettes_t& message, const Rig& rig,
                                   SilhouetteSet* set) {
  set->trigger_seq = message.trigger_seq;
  set->trigger_utime = message.trigger_utime;
  std::vector<CompactSilhouette>* compact = &set->views;
  if (message.num_views != static_cast<int32_t>(message.views.size()) ||
      message.views.size() != rig.cameras.size()) {
    return "expected " + std::to_string(rig.cameras.size()) + " views (one per camera), got " +
           std::to_string(message.views.size());
  }
  compact->resize(rig.cameras.size());
  for (size_t k = 0; k < rig.cameras.size(); ++k) {
    std::string error = ViewFromMessage(message.views[k], rig.cameras[k], &(*compact)[k]);
    if (!error.empty()) return error;
  }
  return {};
}

}  // namespace shapesense
