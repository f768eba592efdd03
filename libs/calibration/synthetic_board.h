#pragma once

// Pictures of a calibration board as a camera would take them, with exact
// ground truth: for the tests and the demo of the calibration tools.
//
// Each pixel is the mean of supersampling^2 rays through the camera model
// (distortion included) intersected with the board's plane, so edges are
// anti-aliased as a real sensor's are; then Gaussian noise. (A pixel whose
// four corners see the same grey is taken as uniform: exact for features
// larger than a pixel, since the board's squares and marker cells are convex.)

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libs/calibration/calibration_board.h"
#include "libs/camera/camera.h"

namespace shapesense {

struct BoardRenderOptions {
  int supersampling = 4;      // rays per pixel along each axis
  double dark = 35.0;         // grey level of dark squares and marker cells
  double light = 215.0;       // grey level of light squares and the margin
  double background = 100.0;  // grey level where no board is
  double noise_sigma = 2.0;   // Gaussian pixel noise, grey levels
  uint32_t seed = 0;          // of the noise

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("supersampling", supersampling, "rays per pixel along each axis (1-16)");
    visit("dark", dark, "grey level of the dark squares (0-255)");
    visit("light", light, "grey level of the light squares (0-255)");
    visit("background", background, "grey level off the board (0-255)");
    visit("noise_sigma", noise_sigma, "Gaussian pixel noise, grey levels (>= 0)");
    visit("seed", seed, "seed of the noise");
  }
  std::string Validate() const;
};

// Renders views of boards through one camera (its intrinsics; its pose is
// ignored), whose rays it computes once.
class BoardViewRenderer {
 public:
  explicit BoardViewRenderer(const Camera& camera);

  // What the camera sees of `board` at `cam_from_board`: an 8-bit grey image
  // of the camera's size. Pixels whose four corners see the same grey are
  // that grey; the others (on an edge) are supersampled. Throws
  // std::invalid_argument on options that fail Validate().
  cv::Mat Render(const CalibrationBoard& board, const Pose3& cam_from_board,
                 const BoardRenderOptions& options = {}) const;

 private:
  int width_;
  int height_;
  std::vector<Vec2> corner_rays_;  // (width + 1) x (height + 1) pixel corners
};

// One view: BoardViewRenderer(camera).Render(board, cam_from_board, options).
cv::Mat RenderBoardView(const Camera& camera, const CalibrationBoard& board,
                        const Pose3& cam_from_board, const BoardRenderOptions& options = {});

}  // namespace shapesense
