#include "libs/calibration/calibration_board.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>

#include "libs/core/error.h"

namespace shapesense {
namespace {

const std::map<std::string, cv::aruco::PREDEFINED_DICTIONARY_NAME>& DictionaryNames() {
  using D = cv::aruco::PREDEFINED_DICTIONARY_NAME;
  static const std::map<std::string, D> names = {
      {"DICT_4X4_50", D::DICT_4X4_50},
      {"DICT_4X4_100", D::DICT_4X4_100},
      {"DICT_4X4_250", D::DICT_4X4_250},
      {"DICT_4X4_1000", D::DICT_4X4_1000},
      {"DICT_5X5_50", D::DICT_5X5_50},
      {"DICT_5X5_100", D::DICT_5X5_100},
      {"DICT_5X5_250", D::DICT_5X5_250},
      {"DICT_5X5_1000", D::DICT_5X5_1000},
      {"DICT_6X6_50", D::DICT_6X6_50},
      {"DICT_6X6_100", D::DICT_6X6_100},
      {"DICT_6X6_250", D::DICT_6X6_250},
      {"DICT_6X6_1000", D::DICT_6X6_1000},
      {"DICT_7X7_50", D::DICT_7X7_50},
      {"DICT_7X7_100", D::DICT_7X7_100},
      {"DICT_7X7_250", D::DICT_7X7_250},
      {"DICT_7X7_1000", D::DICT_7X7_1000},
      {"DICT_ARUCO_ORIGINAL", D::DICT_ARUCO_ORIGINAL},
      {"DICT_APRILTAG_16h5", D::DICT_APRILTAG_16h5},
      {"DICT_APRILTAG_25h9", D::DICT_APRILTAG_25h9},
      {"DICT_APRILTAG_36h10", D::DICT_APRILTAG_36h10},
      {"DICT_APRILTAG_36h11", D::DICT_APRILTAG_36h11},
  };
  return names;
}

// Index of (row, col) in a row-major grid `cols` wide.
size_t GridIndex(int row, int col, int cols) {
  return static_cast<size_t>(row) * static_cast<size_t>(cols) + static_cast<size_t>(col);
}

int DictionarySize(const std::string& name) {
  return cv::aruco::getPredefinedDictionary(DictionaryNames().at(name))->bytesList.rows;
}

// Light squares of a ChArUco board of cols x rows inner corners: each holds a marker.
int CharucoMarkerCount(int cols, int rows) { return (cols + 1) * (rows + 1) / 2; }

cv::Mat ToGray(const cv::Mat& image) {
  if (image.type() == CV_8UC1) return image;
  if (image.type() != CV_8UC3) {
    throw std::invalid_argument("CalibrationBoard::Detect: expected an 8-bit grey or BGR image");
  }
  cv::Mat gray;
  cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  return gray;
}

// Smallest distance between neighbouring corners of a chessboard, px.
double NearestSpacing(const std::vector<cv::Point2f>& corners, int cols) {
  double nearest = 1e9;
  for (size_t i = 0; i + 1 < corners.size(); ++i) {
    if (static_cast<int>(i + 1) % cols != 0) {
      nearest = std::min(nearest, static_cast<double>(cv::norm(corners[i + 1] - corners[i])));
    }
    if (i + static_cast<size_t>(cols) < corners.size()) {
      nearest = std::min(nearest, static_cast<double>(cv::norm(corners[i + cols] - corners[i])));
    }
  }
  return nearest;
}

// Half-size of cornerSubPix's window: 5 (an 11x11 window) where squares are
// large, smaller where the window would reach the neighbouring corners.
int SubPixelHalfWindow(double spacing) { return std::clamp(static_cast<int>(spacing / 3.0), 2, 5); }

cv::TermCriteria SubPixelCriteria() {
  return {cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 1e-4};
}

// Where corner i should be by a homography through its grid neighbours
// (within two rows and columns): exact for a flat board without
// distortion, within a few tenths of a pixel with it.
cv::Point2f PredictFromNeighbours(const std::vector<cv::Point2f>& corners, int cols, int rows,
                                  int i) {
  std::vector<cv::Point2f> board, image;
  const int r0 = i / cols, c0 = i % cols;
  for (int r = std::max(0, r0 - 2); r <= std::min(rows - 1, r0 + 2); ++r) {
    for (int c = std::max(0, c0 - 2); c <= std::min(cols - 1, c0 + 2); ++c) {
      if (r == r0 && c == c0) continue;
      board.emplace_back(static_cast<float>(c), static_cast<float>(r));
      image.push_back(corners[GridIndex(r, c, cols)]);
    }
  }
  const cv::Mat h = cv::findHomography(board, image, 0);
  if (h.empty()) return corners[static_cast<size_t>(i)];
  std::vector<cv::Point2f> predicted;
  cv::perspectiveTransform(
      std::vector<cv::Point2f>{{static_cast<float>(c0), static_cast<float>(r0)}}, predicted, h);
  return predicted[0];
}

// findChessboardCorners sometimes places an outer corner several pixels off,
// on an edge, where cornerSubPix cannot move it. The corner furthest from
// where its neighbours put it is refined again from there, until all agree;
// false when one still does not (the view is then not used). Agreement is
// within a tenth of the corners' spacing: strong lens distortion bends the
// grid by up to ~5% of it over the neighbourhood.
bool RepairStrayCorners(const cv::Mat& gray, int cols, int rows, int half, double spacing,
                        std::vector<cv::Point2f>* corners) {
  const double agreement_px = std::max(1.5, 0.1 * spacing);
  for (int attempt = 0; attempt <= cols * rows; ++attempt) {
    double worst = 0.0;
    int worst_index = -1;
    cv::Point2f worst_prediction;
    for (int i = 0; i < cols * rows; ++i) {
      const cv::Point2f prediction = PredictFromNeighbours(*corners, cols, rows, i);
      const double distance = cv::norm(prediction - (*corners)[static_cast<size_t>(i)]);
      if (distance > worst) {
        worst = distance;
        worst_index = i;
        worst_prediction = prediction;
      }
    }
    if (worst <= agreement_px) return true;
    if (attempt == cols * rows) break;
    std::vector<cv::Point2f> one = {worst_prediction};
    cv::cornerSubPix(gray, one, cv::Size(half, half), cv::Size(-1, -1), SubPixelCriteria());
    if (cv::norm(one[0] - worst_prediction) > agreement_px) return false;
    (*corners)[static_cast<size_t>(worst_index)] = one[0];
  }
  return false;
}

double Cross(const cv::Point2f& a, const cv::Point2f& b) {
  return static_cast<double>(a.x) * b.y - static_cast<double>(a.y) * b.x;
}

// Grey level at the centre of the cell spanned by corners (r, c) .. (r+1, c+1).
double CellBrightness(const cv::Mat& gray, const std::vector<cv::Point2f>& corners, int cols, int r,
                      int c) {
  const auto at = [&](int rr, int cc) { return corners[GridIndex(rr, cc, cols)]; };
  const cv::Point2f centre = 0.25f * (at(r, c) + at(r, c + 1) + at(r + 1, c) + at(r + 1, c + 1));
  cv::Mat patch;
  cv::getRectSubPix(gray, cv::Size(3, 3), centre, patch, CV_32F);
  return cv::mean(patch)[0];
}

// Puts a chessboard's corners in the board's canonical order (see the header):
// first seen from the printed side (x cross y into the image), then corner 0
// at the dark end when the two ends differ in colour.
void CanonicalizeChessboard(const cv::Mat& gray, int cols, int rows,
                            std::vector<cv::Point2f>* corners) {
  std::vector<cv::Point2f>& p = *corners;
  if (Cross(p[1] - p[0], p[static_cast<size_t>(cols)] - p[0]) < 0.0) {
    for (int r = 0; r < rows; ++r) {
      const auto row_start = p.begin() + static_cast<std::ptrdiff_t>(GridIndex(r, 0, cols));
      std::reverse(row_start, row_start + cols);
    }
  }
  if ((cols + rows) % 2 == 0) return;
  const double first = CellBrightness(gray, p, cols, 0, 0);
  const double last = CellBrightness(gray, p, cols, rows - 2, cols - 2);
  if (first > last) std::reverse(p.begin(), p.end());
}

// OpenCV 4.6 returns ChArUco corners 0.5 px down and right of the true
// saddle points (its sub-pixel step shifts them by half a pixel; OpenCV
// issue #25539), so they are refined again here, each with the largest
// window that keeps the markers' edges out, as OpenCV chooses it.
void RefineCharucoCorners(const cv::Mat& gray,
                          const std::vector<std::vector<cv::Point2f>>& marker_corners,
                          std::vector<cv::Point2f>* corners) {
  for (cv::Point2f& corner : *corners) {
    double nearest = 1e9;
    for (const auto& marker : marker_corners) {
      for (const cv::Point2f& m : marker) {
        nearest = std::min(nearest, static_cast<double>(cv::norm(m - corner)));
      }
    }
    const int half = std::clamp(static_cast<int>(0.6 * nearest) - 1, 2, 5);
    std::vector<cv::Point2f> one = {corner};
    cv::cornerSubPix(gray, one, cv::Size(half, half), cv::Size(-1, -1), SubPixelCriteria());
    corner = one[0];
  }
}

BoardObservation ToObservation(const std::vector<cv::Point2f>& corners, std::vector<int> ids) {
  std::vector<size_t> order(ids.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return ids[a] < ids[b]; });
  BoardObservation observation;
  for (const size_t i : order) {
    observation.ids.push_back(ids[i]);
    observation.pixels.emplace_back(corners[i].x, corners[i].y);
  }
  return observation;
}

// Corners all on one row or one column fix no homography: such a view is useless.
bool SpansTwoDimensions(const std::vector<int>& ids, int cols) {
  std::set<int> board_rows, board_cols;
  for (const int id : ids) {
    board_rows.insert(id / cols);
    board_cols.insert(id % cols);
  }
  return board_rows.size() >= 2 && board_cols.size() >= 2;
}

}  // namespace

std::string BoardOptions::Validate() const {
  if (pattern != "chessboard" && pattern != "charuco") {
    return "pattern: expected chessboard or charuco, got " + pattern;
  }
  if (cols < 3 || rows < 3) {
    return "cols, rows: expected at least 3 inner corners each, got " + std::to_string(cols) +
           " x " + std::to_string(rows);
  }
  if (!std::isfinite(square) || square <= 0.0) {
    return "square: expected a positive size, mm, got " + Number(square);
  }
  if (!std::isfinite(marker) || marker < 0.0 || marker >= square) {
    return "marker: expected 0 (0.75 * square) or a size below square (" + Number(square) +
           " mm), got " + Number(marker);
  }
  if (!DictionaryNames().contains(dictionary)) {
    return "dictionary: expected an OpenCV ArUco dictionary name such as DICT_5X5_100, got " +
           dictionary;
  }
  if (pattern == "charuco" && DictionarySize(dictionary) < CharucoMarkerCount(cols, rows)) {
    return "dictionary: " + dictionary + " has " + std::to_string(DictionarySize(dictionary)) +
           " markers, the board needs " + std::to_string(CharucoMarkerCount(cols, rows));
  }
  if (min_corners < 4) {
    return "min_corners: expected at least 4, got " + std::to_string(min_corners);
  }
  return "";
}

std::vector<std::string> KnownDictionaries() {
  std::vector<std::string> names;
  for (const auto& [name, value] : DictionaryNames()) names.push_back(name);
  return names;
}

// The ChArUco board of OpenCV and, for rendering, each marker's cells.
struct CalibrationBoard::Markers {
  cv::Ptr<cv::aruco::Dictionary> dictionary;
  cv::Ptr<cv::aruco::CharucoBoard> board;
  std::vector<int> marker_of_square;  // per square, row-major; -1 on dark squares
  std::vector<cv::Mat> cells;         // per marker: one 8-bit pixel per cell, border included
};

CalibrationBoard::CalibrationBoard(const BoardOptions& options) : options_(options) {
  if (const std::string error = options_.Validate(); !error.empty()) {
    throw InputError("board: " + error);
  }
  if (options_.marker == 0.0) options_.marker = 0.75 * options_.square;
  if (!is_charuco()) return;
  markers_ = std::make_unique<Markers>();
  markers_->dictionary =
      cv::aruco::getPredefinedDictionary(DictionaryNames().at(options_.dictionary));
  markers_->board = cv::aruco::CharucoBoard::create(
      options_.cols + 1, options_.rows + 1, static_cast<float>(options_.square),
      static_cast<float>(options_.marker), markers_->dictionary);
  const int squares_x = options_.cols + 1;
  markers_->marker_of_square.assign(GridIndex(options_.rows + 1, 0, squares_x), -1);
  const int cells = markers_->dictionary->markerSize + 2;
  for (size_t k = 0; k < markers_->board->objPoints.size(); ++k) {
    const cv::Point3f top_left = markers_->board->objPoints[k][0];
    const int square_x = static_cast<int>(top_left.x / options_.square);
    const int square_y = static_cast<int>(top_left.y / options_.square);
    markers_->marker_of_square[GridIndex(square_y, square_x, squares_x)] = static_cast<int>(k);
    cv::Mat marker_cells;
    markers_->dictionary->drawMarker(markers_->board->ids[k], cells, marker_cells, 1);
    markers_->cells.push_back(marker_cells);
  }
}

CalibrationBoard::~CalibrationBoard() = default;

Vec3 CalibrationBoard::CornerPoint(int id) const {
  const int row = id / options_.cols;
  const int col = id % options_.cols;
  return Vec3(col * options_.square, row * options_.square, 0.0);
}

std::vector<Vec3> CalibrationBoard::CornerPoints(const std::vector<int>& ids) const {
  std::vector<Vec3> points;
  points.reserve(ids.size());
  for (const int id : ids) points.push_back(CornerPoint(id));
  return points;
}

bool CalibrationBoard::IsOrientationUnambiguous() const {
  return is_charuco() || (options_.cols + options_.rows) % 2 == 1;
}

std::string CalibrationBoard::Describe() const {
  std::ostringstream out;
  out << options_.pattern << " " << options_.cols << "x" << options_.rows << " inner corners, "
      << options_.square << " mm squares";
  if (is_charuco()) out << ", " << options_.marker << " mm markers of " << options_.dictionary;
  return out.str();
}

std::optional<BoardObservation> CalibrationBoard::Detect(const cv::Mat& image) const {
  const cv::Mat gray = ToGray(image);
  return is_charuco() ? DetectCharuco(gray) : DetectChessboard(gray);
}

std::optional<BoardObservation> CalibrationBoard::DetectChessboard(const cv::Mat& gray) const {
  std::vector<cv::Point2f> corners;
  const int flags =
      cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK;
  if (!cv::findChessboardCorners(gray, cv::Size(options_.cols, options_.rows), corners, flags)) {
    return std::nullopt;
  }
  const double spacing = NearestSpacing(corners, options_.cols);
  const int half = SubPixelHalfWindow(spacing);
  cv::cornerSubPix(gray, corners, cv::Size(half, half), cv::Size(-1, -1), SubPixelCriteria());
  if (!RepairStrayCorners(gray, options_.cols, options_.rows, half, spacing, &corners)) {
    return std::nullopt;
  }
  CanonicalizeChessboard(gray, options_.cols, options_.rows, &corners);
  std::vector<int> ids(corners.size());
  std::iota(ids.begin(), ids.end(), 0);
  return ToObservation(corners, ids);
}

std::optional<BoardObservation> CalibrationBoard::DetectCharuco(const cv::Mat& gray) const {
  std::vector<std::vector<cv::Point2f>> marker_corners;
  std::vector<int> marker_ids;
  cv::aruco::detectMarkers(gray, markers_->dictionary, marker_corners, marker_ids);
  if (marker_ids.empty()) return std::nullopt;
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  cv::aruco::interpolateCornersCharuco(marker_corners, marker_ids, gray, markers_->board, corners,
                                       ids);
  // OpenCV numbers ChArUco corners as this board does (row-major inner corners).
  if (static_cast<int>(ids.size()) < options_.min_corners ||
      !SpansTwoDimensions(ids, options_.cols)) {
    return std::nullopt;
  }
  RefineCharucoCorners(gray, marker_corners, &corners);
  return ToObservation(corners, ids);
}

std::optional<double> CalibrationBoard::Reflectance(double x, double y) const {
  const double s = options_.square;
  // Squares (0, 0) .. (cols, rows); square (0, 0) lies diagonally outside corner 0.
  const int square_x = static_cast<int>(std::floor(x / s)) + 1;
  const int square_y = static_cast<int>(std::floor(y / s)) + 1;
  if (square_x < -1 || square_y < -1 || square_x > options_.cols + 1 ||
      square_y > options_.rows + 1) {
    return std::nullopt;
  }
  if (square_x < 0 || square_y < 0 || square_x > options_.cols || square_y > options_.rows) {
    return 1.0;  // the margin
  }
  if ((square_x + square_y) % 2 == 0) return 0.0;
  if (!is_charuco()) return 1.0;
  return MarkerReflectance(square_x, square_y, x + s, y + s);
}

// (x, y) in OpenCV's ChArUco board frame, whose origin is the board's outer corner.
std::optional<double> CalibrationBoard::MarkerReflectance(int square_x, int square_y, double x,
                                                          double y) const {
  const int index = markers_->marker_of_square[GridIndex(square_y, square_x, options_.cols + 1)];
  if (index < 0) return 1.0;
  const cv::Mat& cells = markers_->cells[static_cast<size_t>(index)];
  const cv::Point3f top_left = markers_->board->objPoints[static_cast<size_t>(index)][0];
  const double cell = options_.marker / cells.cols;
  const int u = static_cast<int>(std::floor((x - top_left.x) / cell));
  const int v = static_cast<int>(std::floor((y - top_left.y) / cell));
  if (u < 0 || v < 0 || u >= cells.cols || v >= cells.rows) return 1.0;
  return cells.at<uint8_t>(v, u) / 255.0;
}

}  // namespace shapesense
