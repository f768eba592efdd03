#pragma once

// Multi-camera extrinsics from a board seen by several cameras at once.
//
// First poses: each camera's view of the board by planar PnP; cameras and
// board poses are then chained through the views they share. Then one Ceres
// problem refines all camera poses and board poses together (and, when
// asked, every camera's intrinsics) by minimising the reprojection error of
// every corner, with a Huber loss; observations that still spoil the fit are
// left out and the problem solved again.
//
// The world frame is anchored to the board of one view: origin at its
// corner 0, x along the board's rows (corner 0 -> 1), z out of the board's
// printed side (towards the cameras that see it; up for a board lying on a
// table), y = z cross x. Or, when anchor points are given, to the frame of
// those points: the known world positions of some corners of that view.

#include <optional>
#include <string>
#include <vector>

#include "libs/calibration/calibration_board.h"
#include "libs/camera/camera.h"

namespace shapesense {

struct ExtrinsicsOptions {
  // The view whose board pose (or anchor points) defines the world frame.
  int anchor_view = 0;
  // Refine every camera's intrinsics with the poses (many views spread over
  // each image are needed for it to help).
  bool refine_intrinsics = false;
  // Huber loss scale, px. 0: plain least squares.
  double loss_scale_px = 2.0;
  int max_iterations = 100;
  // An observation (one camera's view of the board) spoils the fit when its
  // reprojection RMS exceeds both outlier_factor times the median
  // observation's and outlier_floor_px; it is then left out.
  double outlier_factor = 4.0;
  double outlier_floor_px = 1.0;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("anchor_view", anchor_view, "view whose board pose defines the world frame (>= 0)");
    visit("refine_intrinsics", refine_intrinsics, "refine the intrinsics with the poses");
    visit("loss_scale_px", loss_scale_px, "Huber loss scale, px (0: plain least squares)");
    visit("max_iterations", max_iterations, "solver iterations (> 0)");
    visit("outlier_factor", outlier_factor,
          "an observation is left out above this times the median's RMS (> 1)");
    visit("outlier_floor_px", outlier_floor_px, "... and above this RMS, px (>= 0)");
  }
  std::string Validate() const;
};

// A board corner of the anchor view whose world position is known.
struct AnchorPoint {
  int corner = 0;             // corner id, r * cols + c
  Vec3 world = Vec3::Zero();  // mm
};

struct ExtrinsicsInput {
  // Names and intrinsics; their poses are what is estimated.
  std::vector<Camera> cameras;
  // One name per view, for messages.
  std::vector<std::string> view_names;
  // observations[camera][view]: the board in that camera's image of the view,
  // nullopt where it was not found. View v of every camera is the same instant.
  std::vector<std::vector<std::optional<BoardObservation>>> observations;
  // Optional: at least 3 non-collinear corners of the anchor view with their
  // world positions; empty anchors the world to that view's board.
  std::vector<AnchorPoint> anchor_points;
};

// One camera's view of the board under the final model.
struct ObservationFit {
  bool used = true;  // false: it spoiled the fit and was left out
  double rms_px = 0.0;
  std::vector<Vec2> reprojected;  // its corners as the model projects them
};

struct ExtrinsicsResult {
  // The input cameras with cam_from_world in the world frame (and refined
  // intrinsics when asked).
  std::vector<Camera> cameras;
  // Per view; nullopt when no camera saw its board.
  std::vector<std::optional<Pose3>> world_from_board;
  // fits[camera][view], where the board was found.
  std::vector<std::vector<std::optional<ObservationFit>>> fits;
  std::vector<double> camera_rms_px;  // over each camera's used observations
  double rms_px = 0.0;                // over all used observations
  double anchor_rms_mm = 0.0;         // fit of the anchor points, when given
  int iterations = 0;                 // of the last solve
  std::string solver_report;          // Ceres' one-line report of the last solve
};

// Throws InputError naming the camera or view on input that cannot give a
// rig: a camera that never sees the board, cameras not linked to the others
// by shared views, an anchor view no camera saw, bad anchor points, or a
// chessboard whose corner numbering turns with it (cols + rows even) when
// there are several cameras; std::invalid_argument on mismatched sizes or
// options that fail Validate().
ExtrinsicsResult CalibrateExtrinsics(const ExtrinsicsInput& input, const CalibrationBoard& board,
                                     const ExtrinsicsOptions& options,
                                     const CalibrationProgress& progress = {});

}  // namespace shapesense
