#pragma once

// Pictures for people checking a calibration (pure drawing; the tools write them).

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libs/calibration/calibration_board.h"
#include "libs/calibration/point_registration.h"

namespace shapesense {

// One view: detected corners (green circles; corner 0 ringed in blue, with
// an arrow to corner 1), their reprojections through the fitted model (red
// crosses), each error magnified `error_scale` times (yellow line), and a
// caption. A view left out of the fit gets a red frame and "LEFT OUT".
// `reprojected` may be empty (no fit). Returns an 8-bit BGR image.
cv::Mat DrawCornerOverlay(const cv::Mat& image, const BoardObservation& detected,
                          const std::vector<Vec2>& reprojected, const std::string& caption,
                          bool left_out, double error_scale = 10.0);

// The registration's errors: per point, bars of the x, y and z error
// (red, green, blue) and the 3-D error (grey), with the RMS per axis; beside
// it a top view (x-y) of the reference points with each error drawn as a
// magnified arrow. 8-bit BGR, about 1000 x 460 px.
cv::Mat DrawRegistrationPlot(const std::vector<Vec3>& reference,
                             const PointRegistration& registration);

}  // namespace shapesense
