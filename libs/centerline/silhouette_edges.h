#pragma once

#include <optional>

#include "libs/geometry/types.h"
#include "libs/silhouette/silhouette.h"

namespace shapesense {

// Where a walk from inside the silhouette leaves it, to a fraction of a pixel.
//
// The walk steps one pixel at a time along `direction` (unit, image) from
// `start` while the mask is set. The edge is then placed on the `difference`
// image, sampled along the same line: at the crossing of the level halfway
// between the body just inside and the backdrop just outside (the backdrop
// need not be 0: a shadow there raises it). For an anti-aliased step edge this
// crossing is where the tube's outline cuts the line.
//
// nullopt when the start is outside the mask or the image, the walk leaves
// the image, the mask does not end within `max_steps` (another part of the
// tube continues it), or the contrast is too low to place the edge.
// Otherwise the distance from `start` to the edge, px.
std::optional<double> FindEdgeAlong(const Silhouette& silhouette, const Vec2& start,
                                    const Vec2& direction, int max_steps);

// Bilinear sample of a CV_8U image at a pixel position (pixel centres at
// integers); the position must be at least one pixel inside the border.
double SampleBilinear(const cv::Mat& image, const Vec2& position);

}  // namespace shapesense
