#include "services/controller/controller_inputs.h"

#include <cmath>
#include <cstdio>

namespace shapesense {
namespace {

// An age past this is garbage, not a stale shape (which the watchdog handles), µs.
constexpr int64_t kLargestAge = 3'600'000'000;
constexpr double kStartWindow = 60e6;    // µs
constexpr double kLongestMove = 3600.0;  // s

bool AllFinite(const double* values, int count) {
  for (int i = 0; i < count; ++i) {
    if (!std::isfinite(values[i])) return false;
  }
  return true;
}

}  // namespace

ShapeUse CheckShape(const shape_t& shape, std::string* why) {
  if (!shape.valid || !shape.has_configuration) {
    *why = shape.valid ? "no configuration" : "not measured: " + shape.error;
    return ShapeUse::kNoConfiguration;
  }
  if (!AllFinite(shape.q, 4)) {
    *why = "q: expected finite numbers";
  } else if (shape.trigger_utime <= 0) {
    *why = "trigger_utime: expected a time, got " + std::to_string(shape.trigger_utime);
  } else if (shape.header.data_age_us < 0 || shape.header.data_age_us > kLargestAge) {
    *why = "data_age_us: expected 0 to " + std::to_string(kLargestAge) + " µs, got " +
           std::to_string(shape.header.data_age_us);
  } else {
    why->clear();
    return ShapeUse::kUsable;
  }
  return ShapeUse::kMalformed;
}

shape_t LoggedShape(const shape_t& shape) {
  shape_t logged = shape;
  logged.num_points = 0;
  logged.centerline.clear();
  logged.arc_length.clear();
  logged.curvature.clear();
  logged.num_markers = 0;
  logged.markers.clear();
  logged.marker_arc_length.clear();
  logged.marker_std_mm.clear();
  return logged;
}

bool TargetFromMessage(const configuration_target_t& message, int64_t now_utime, Target* target,
                       std::string* why) {
  if (message.kind != configuration_target_t::KIND_CONFIGURATION &&
      message.kind != configuration_target_t::KIND_TIP) {
    *why = "kind: expected KIND_CONFIGURATION (1) or KIND_TIP (2), got " +
           std::to_string(message.kind);
  } else if (!(message.duration_s >= 0.0 && message.duration_s <= kLongestMove)) {
    *why = "duration_s: expected 0-3600 s, got " + std::to_string(message.duration_s);
  } else if (message.start_utime != 0 && std::abs(static_cast<double>(message.start_utime) -
                                                  static_cast<double>(now_utime)) > kStartWindow) {
    *why = "start_utime: expected 0 or within a minute of the controller's clock";
  } else {
    *target = Target{};
    if (message.kind == configuration_target_t::KIND_TIP) {
      target->kind = TargetKind::kTipPosition;
      target->tip = Vec3(message.tip[0], message.tip[1], message.tip[2]);
    } else {
      target->configuration = Configuration(message.q[0], message.q[1], message.q[2], message.q[3]);
    }
    return true;
  }
  return false;
}

Configuration TargetRamp::At(double time) const {
  // A target set to start later holds the previous one until then.
  if (time < start) return from;
  if (!(duration > 0.0) || time >= start + duration) return to;
  const double fraction = (time - start) / duration;
  return from + fraction * (to - from);
}

}  // namespace shapesense
