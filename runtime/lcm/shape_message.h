#pragma once

// shape_t and the shape estimate (and the configuration q it may carry),
// both ways.
// Every message from the network is checked field by field before use: a
// malformed one yields a reason ("cam0: size: expected 921600 bytes
// (row_stride 1920 x height 480), got 1000"), never a crash. Messages built
// here from the libraries' types are always valid.
#include <optional>
#include <string>

#include "libs/centerline/shape_estimator.h"
#include "libs/mechanics/configuration.h"
#include "shapesense/shape_t.hpp"

namespace shapesense {

// shape_t has no field for the tube radius: it does not survive the round trip.

// Everything of the estimate (an invalid one carries only its error);
// header, trigger and stage times are the caller's.
shape_t ShapeToMessage(const ShapeEstimate& shape);
// Checks the counts and that the numbers are finite; "" or the reason.
std::string ValidateShapeMessage(const shape_t& message);
std::string ShapeFromMessage(const shape_t& message, ShapeEstimate* shape);
// Sets has_configuration, q and configuration_residual_mm (the arc fit's RMS
// residual, mm; 0 for a true configuration).
void SetMessageConfiguration(const Configuration& q, double residual_mm, shape_t* message);
// The message's q, when it has one.
std::optional<Configuration> MessageConfiguration(const shape_t& message);

// ---- stage_time_t ----------------------------------------------------------

}  // namespace shapesense
