// Boards: options, the drawn pattern against OpenCV's own ChArUco drawing,
// and detection on rendered views against the projected truth.
#include "libs/calibration/calibration_board.h"

#include <gtest/gtest.h>

#include <opencv2/aruco/charuco.hpp>

#include "libs/calibration/synthetic_board.h"
#include "libs/core/error.h"
#include "tests/libs/calibration/calibration_scenes.h"

namespace shapesense {
namespace {

using testing::IntrinsicsBoardPose;
using testing::ThreeCameraRig;

BoardOptions Chessboard(int cols = 9, int rows = 6, double square = 25.0) {
  BoardOptions options;
  options.cols = cols;
  options.rows = rows;
  options.square = square;
  return options;
}

BoardOptions Charuco(int cols = 6, int rows = 4, double square = 30.0) {
  BoardOptions options = Chessboard(cols, rows, square);
  options.pattern = "charuco";
  return options;
}

struct CornerErrors {
  double rms = 0.0;
  double largest = 0.0;
};

// Distances of detected corners from the true projections of their ids, px.
CornerErrors MeasureCorners(const Camera& camera, const CalibrationBoard& board,
                            const Pose3& cam_from_board, const BoardObservation& seen) {
  CornerErrors errors;
  for (size_t i = 0; i < seen.size(); ++i) {
    const Vec3 p = cam_from_board * board.CornerPoint(seen.ids[i]);
    const Vec2 truth = camera.DistortAndScale(Vec2(p.x() / p.z(), p.y() / p.z()));
    errors.rms += (truth - seen.pixels[i]).squaredNorm();
    errors.largest = std::max(errors.largest, (truth - seen.pixels[i]).norm());
  }
  errors.rms = std::sqrt(errors.rms / static_cast<double>(seen.size()));
  return errors;
}

TEST(BoardOptionsTest, DefaultsAreValidAndBadValuesNameTheirKey) {
  EXPECT_EQ(BoardOptions{}.Validate(), "");
  EXPECT_EQ(Charuco().Validate(), "");
  BoardOptions bad = Chessboard();
  bad.pattern = "circles";
  EXPECT_NE(bad.Validate().find("pattern:"), std::string::npos);
  bad = Chessboard(2, 6);
  EXPECT_NE(bad.Validate().find("cols, rows:"), std::string::npos);
  bad = Chessboard(9, 6, -1.0);
  EXPECT_NE(bad.Validate().find("square:"), std::string::npos);
  bad = Charuco();
  bad.marker = 40.0;
  EXPECT_NE(bad.Validate().find("marker:"), std::string::npos);
  bad.marker = 0.0;
  bad.dictionary = "DICT_9X9_1";
  EXPECT_NE(bad.Validate().find("dictionary:"), std::string::npos);
  bad = Charuco(20, 20);  // 220 markers do not fit DICT_5X5_100
  EXPECT_NE(bad.Validate().find("dictionary:"), std::string::npos);
  EXPECT_THROW(CalibrationBoard{bad}, InputError);
}

TEST(CalibrationBoardTest, CornerIdsAreRowMajorFromCornerZero) {
  const CalibrationBoard board(Chessboard(9, 6, 25.0));
  EXPECT_EQ(board.NumCorners(), 54);
  EXPECT_TRUE(board.CornerPoint(0).isZero());
  EXPECT_TRUE(board.CornerPoint(1).isApprox(Vec3(25, 0, 0)));
  EXPECT_TRUE(board.CornerPoint(9).isApprox(Vec3(0, 25, 0)));
  EXPECT_TRUE(board.CornerPoint(53).isApprox(Vec3(200, 125, 0)));
  EXPECT_TRUE(board.IsOrientationUnambiguous());
  EXPECT_FALSE(CalibrationBoard(Chessboard(7, 7)).IsOrientationUnambiguous());
  EXPECT_TRUE(CalibrationBoard(Charuco(5, 5)).IsOrientationUnambiguous());
}

// The reflectance the renderer uses must be OpenCV's own ChArUco board,
// markers included, or detection of rendered views would test nothing.
TEST(CalibrationBoardTest, CharucoReflectanceMatchesOpenCvDrawing) {
  const BoardOptions options = Charuco(5, 4, 30.0);
  const CalibrationBoard board(options);
  constexpr int kPxPerMm = 4;
  const auto opencv_board = cv::aruco::CharucoBoard::create(
      6, 5, 30.f, 22.5f, cv::aruco::getPredefinedDictionary(cv::aruco::DICT_5X5_100));
  cv::Mat drawn;
  opencv_board->draw(cv::Size(180 * kPxPerMm, 150 * kPxPerMm), drawn, 0, 1);
  int differing = 0;
  for (int v = 0; v < drawn.rows; ++v) {
    for (int u = 0; u < drawn.cols; ++u) {
      // OpenCV's board frame starts at the outer corner, one square before corner 0.
      const double x = (u + 0.5) / kPxPerMm - 30.0, y = (v + 0.5) / kPxPerMm - 30.0;
      const double mine = board.Reflectance(x, y).value() * 255.0;
      differing += std::abs(mine - drawn.at<uint8_t>(v, u)) > 128 ? 1 : 0;
    }
  }
  // Only pixels on an edge may differ (OpenCV rounds marker cells to pixels).
  EXPECT_LT(differing, drawn.rows * drawn.cols / 100);
  EXPECT_EQ(board.Reflectance(-35.0, 0.0).value(), 1.0);  // the margin
  EXPECT_FALSE(board.Reflectance(-65.0, 0.0).has_value());
}

TEST(CalibrationBoardTest, FindsRenderedChessboardCornersToATenthOfAPixel) {
  const CalibrationBoard board(Chessboard());
  const Camera camera = ThreeCameraRig()[0];
  const BoardViewRenderer renderer(camera);
  std::mt19937 rng(1);
  for (uint32_t seed = 0; seed < 4; ++seed) {
    const Pose3 cam_from_board = IntrinsicsBoardPose(camera, board, rng);
    BoardRenderOptions render;
    render.seed = seed;
    const std::optional<BoardObservation> seen =
        board.Detect(renderer.Render(board, cam_from_board, render));
    ASSERT_TRUE(seen.has_value()) << "view " << seed;
    ASSERT_EQ(seen->size(), 54u);
    // Canonical numbering: whatever the in-plane turn, ids are the board's own.
    const CornerErrors errors = MeasureCorners(camera, board, cam_from_board, *seen);
    EXPECT_LT(errors.rms, 0.1) << "view " << seed;
    EXPECT_LT(errors.largest, 0.3) << "view " << seed;
  }
}

TEST(CalibrationBoardTest, FindsRenderedCharucoCornersEvenWhenPartlyOutOfView) {
  const CalibrationBoard board(Charuco(7, 5, 30.0));
  const Camera camera = ThreeCameraRig()[1];
  const BoardViewRenderer renderer(camera);
  std::mt19937 rng(2);
  for (int k = 0; k < 3; ++k) {
    Pose3 cam_from_board = IntrinsicsBoardPose(camera, board, rng);
    if (k == 2) cam_from_board.translation().x() += 120.0;  // push part of it out of the image
    const std::optional<BoardObservation> seen =
        board.Detect(renderer.Render(board, cam_from_board));
    ASSERT_TRUE(seen.has_value()) << "view " << k;
    // A corner needs a whole marker beside it, which the image's edge may cut.
    EXPECT_GE(seen->size(), k < 2 ? 28u : 8u);
    EXPECT_TRUE(std::is_sorted(seen->ids.begin(), seen->ids.end()));
    // Also catches OpenCV 4.6's half-pixel shift of ChArUco corners.
    const CornerErrors errors = MeasureCorners(camera, board, cam_from_board, *seen);
    EXPECT_LT(errors.rms, 0.1) << "view " << k;
    EXPECT_LT(errors.largest, 0.3) << "view " << k;
  }
}

TEST(CalibrationBoardTest, FindsNothingWithoutTheBoardOrWithTheWrongSize) {
  const Camera camera = ThreeCameraRig()[0];
  const CalibrationBoard board(Chessboard(9, 6));
  std::mt19937 rng(3);
  const cv::Mat view = RenderBoardView(camera, board, IntrinsicsBoardPose(camera, board, rng));
  EXPECT_FALSE(CalibrationBoard(Chessboard(8, 6)).Detect(view).has_value());
  EXPECT_FALSE(CalibrationBoard(Charuco(9, 6)).Detect(view).has_value());
  const cv::Mat blank(480, 640, CV_8UC3, cv::Scalar(90, 90, 90));
  EXPECT_FALSE(board.Detect(blank).has_value());
  EXPECT_THROW(board.Detect(cv::Mat(10, 10, CV_32F)), std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
