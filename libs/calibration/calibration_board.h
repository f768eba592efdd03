#pragma once

// Calibration boards (chessboard and ChArUco) and their detection in images.
//
// Both patterns are described by their inner corners, `cols` x `rows`, and
// share one board frame: corner id = r * cols + c sits at (c, r, 0) * square
// (mm), x along a row, y down the columns, z = x cross y (into the board, away
// from a camera that sees its printed side). The square diagonally outside
// corner 0 is dark. A ChArUco board of cols x rows inner corners has
// (cols + 1) x (rows + 1) squares, its markers in the light ones.
//
// A chessboard is found whole or not at all; its corner order is made
// canonical (the board seen from its printed side, corner 0 at the dark outer
// square) so that every camera of a rig numbers the corners alike. That is
// only possible when cols + rows is odd (e.g. 9 x 6): otherwise the board
// looks the same turned by 180 degrees (see IsOrientationUnambiguous). A
// ChArUco board may be seen in part; its markers name every corner.

#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "libs/geometry/types.h"

namespace shapesense {

// Called with the fraction done (0-1) and what is being done.
using CalibrationProgress = std::function<void(double fraction, const std::string& stage)>;

struct BoardOptions {
  // "chessboard" or "charuco".
  std::string pattern = "chessboard";
  // Inner corners along a row and down a column.
  int cols = 9;
  int rows = 6;
  // Side of one square, mm.
  double square = 25.0;
  // ChArUco: side of one marker, mm; 0 takes 0.75 * square.
  double marker = 0.0;
  // ChArUco: the marker dictionary, by its OpenCV name.
  std::string dictionary = "DICT_5X5_100";
  // ChArUco: fewest corners for a view to count.
  int min_corners = 8;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("pattern", pattern, "board pattern: chessboard or charuco");
    visit("cols", cols, "inner corners along a row (>= 2)");
    visit("rows", rows, "inner corners down a column (>= 2)");
    visit("square", square, "side of one square, mm (> 0)");
    visit("marker", marker, "ChArUco marker side, mm (0: 0.75 * square; < square)");
    visit("dictionary", dictionary, "ChArUco dictionary, e.g. DICT_5X5_100, DICT_6X6_250");
    visit("min_corners", min_corners, "ChArUco: fewest corners for a view to count (>= 6)");
  }
  std::string Validate() const;
};

// The dictionary names BoardOptions::dictionary accepts.
std::vector<std::string> KnownDictionaries();

// Board corners found in one image: ids (ascending) and sub-pixel positions
// (OpenCV's convention: pixel (0, 0) is the centre of the top-left pixel).
struct BoardObservation {
  std::vector<int> ids;
  std::vector<Vec2> pixels;

  size_t size() const { return ids.size(); }
};

class CalibrationBoard {
 public:
  // Throws InputError("board: key: expected ...") on options that fail Validate().
  explicit CalibrationBoard(const BoardOptions& options);
  ~CalibrationBoard();
  CalibrationBoard(const CalibrationBoard&) = delete;
  CalibrationBoard& operator=(const CalibrationBoard&) = delete;

  const BoardOptions& options() const { return options_; }
  bool is_charuco() const { return options_.pattern == "charuco"; }
  int NumCorners() const { return options_.cols * options_.rows; }
  // Board frame position of a corner, mm.
  Vec3 CornerPoint(int id) const;
  std::vector<Vec3> CornerPoints(const std::vector<int>& ids) const;
  // Whether the board's corner numbering is the same however it is turned
  // (always for ChArUco; for a chessboard when cols + rows is odd).
  bool IsOrientationUnambiguous() const;
  // "chessboard 9x6 inner corners, 25 mm squares", for messages.
  std::string Describe() const;

  // Finds the board in an 8-bit grey or BGR image; nullopt when it is not
  // there (or, for ChArUco, fewer than min_corners corners are).
  std::optional<BoardObservation> Detect(const cv::Mat& image) const;

  // The board's reflectance at a point of its plane (board frame, mm): 0 on
  // dark, 1 on light squares and marker cells; the board has a light margin
  // one square wide around its squares; nullopt beyond it.
  std::optional<double> Reflectance(double x, double y) const;

 private:
  struct Markers;
  std::optional<BoardObservation> DetectChessboard(const cv::Mat& gray) const;
  std::optional<BoardObservation> DetectCharuco(const cv::Mat& gray) const;
  std::optional<double> MarkerReflectance(int square_x, int square_y, double x, double y) const;

  BoardOptions options_;
  std::unique_ptr<Markers> markers_;  // ChArUco only
};

}  // namespace shapesense
