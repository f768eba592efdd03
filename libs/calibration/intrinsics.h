#pragma once

// Camera intrinsics from views of a board: OpenCV's calibrateCamera (Zhang's
// method and Levenberg-Marquardt over the pinhole model with k1 k2 p1 p2 k3),
// with views that spoil the fit found by their reprojection error, flagged
// and left out one at a time, worst first, until none is left to flag.

#include <string>
#include <vector>

#include "libs/calibration/calibration_board.h"
#include "libs/camera/camera.h"

namespace shapesense {

struct IntrinsicsOptions {
  // Hold k3 at 0 (lenses of long focal length, few views).
  bool fix_k3 = false;
  // Hold p1 = p2 = 0.
  bool zero_tangential = false;
  // Hold fx = fy.
  bool fix_aspect_ratio = false;
  // Hold the principal point at the image centre.
  bool fix_principal_point = false;
  // A view spoils the fit when its reprojection RMS exceeds both
  // outlier_factor times the median view's and outlier_floor_px.
  double outlier_factor = 3.0;
  double outlier_floor_px = 0.5;
  // Fewest views to calibrate from; flagging stops before it.
  int min_views = 3;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("fix_k3", fix_k3, "hold the distortion coefficient k3 at 0");
    visit("zero_tangential", zero_tangential, "hold the tangential distortion p1, p2 at 0");
    visit("fix_aspect_ratio", fix_aspect_ratio, "hold fx = fy");
    visit("fix_principal_point", fix_principal_point, "hold the principal point at the centre");
    visit("outlier_factor", outlier_factor,
          "a view is flagged above this times the median view's RMS (> 1)");
    visit("outlier_floor_px", outlier_floor_px,
          "... and above this RMS, px (>= 0): views below it never spoil the fit");
    visit("min_views", min_views, "fewest views to calibrate from (>= 3)");
  }
  std::string Validate() const;
};

// One view under the final model.
struct ViewFit {
  bool used = true;     // false: flagged as spoiling the fit, left out
  double rms_px = 0.0;  // reprojection RMS of its corners
  Pose3 cam_from_board = Pose3::Identity();
  std::vector<Vec2> reprojected;  // its corners as the model projects them
};

struct IntrinsicsResult {
  Camera camera;               // size, camera_matrix, distortion; name empty, pose identity
  double rms_px = 0.0;         // reprojection RMS over the corners of the used views
  std::vector<ViewFit> views;  // one per input view, in order

  int UsedViews() const;
};

// Calibrates from views of `board` in images of width x height. Throws
// InputError when fewer than options.min_views views are given, or OpenCV
// cannot calibrate from them (e.g. all views alike); std::invalid_argument
// on options that fail Validate().
IntrinsicsResult CalibrateIntrinsics(const std::vector<BoardObservation>& views,
                                     const CalibrationBoard& board, int width, int height,
                                     const IntrinsicsOptions& options,
                                     const CalibrationProgress& progress = {});

}  // namespace shapesense
