// Intrinsics: rendered views with known truth, a view that spoils the fit,
// and OpenCV's sample pictures against OpenCV's own calibrateCamera.
#include "libs/calibration/intrinsics.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "libs/calibration/synthetic_board.h"
#include "libs/core/error.h"
#include "tests/libs/calibration/calibration_scenes.h"

namespace shapesense {
namespace {

using testing::IntrinsicsBoardPose;
using testing::OpenCvSampleDir;
using testing::OpenCvSampleNumbers;
using testing::ThreeCameraRig;

BoardOptions NineBySix(double square = 25.0) {
  BoardOptions options;
  options.cols = 9;
  options.rows = 6;
  options.square = square;
  return options;
}

std::vector<BoardObservation> RenderedViews(const Camera& camera, const CalibrationBoard& board,
                                            int count, uint32_t seed) {
  const BoardViewRenderer renderer(camera);
  std::mt19937 rng(seed);
  std::vector<BoardObservation> views;
  for (int i = 0; i < count; ++i) {
    BoardRenderOptions render;
    render.seed = seed * 100 + static_cast<uint32_t>(i);
    const cv::Mat image = renderer.Render(board, IntrinsicsBoardPose(camera, board, rng), render);
    std::optional<BoardObservation> seen = board.Detect(image);
    if (seen) views.push_back(*seen);
  }
  return views;
}

void ExpectNearTruth(const Camera& truth, const Camera& estimate, double lens_tolerance_px = 1.0) {
  const Mat3& k = estimate.camera_matrix;
  EXPECT_NEAR(k(0, 0) / truth.camera_matrix(0, 0), 1.0, 0.005);
  EXPECT_NEAR(k(1, 1) / truth.camera_matrix(1, 1), 1.0, 0.005);
  EXPECT_NEAR(k(0, 2), truth.camera_matrix(0, 2), 3.0);
  EXPECT_NEAR(k(1, 2), truth.camera_matrix(1, 2), 3.0);
  // The lens as a whole: the same pixel for rays across the image (the
  // coefficients alone trade off against each other).
  for (const Vec2& n : {Vec2(0.0, 0.0), Vec2(0.3, 0.2), Vec2(-0.3, 0.2), Vec2(0.25, -0.25)}) {
    EXPECT_LT((estimate.DistortAndScale(n) - truth.DistortAndScale(n)).norm(), lens_tolerance_px)
        << n.transpose();
  }
}

TEST(IntrinsicsTest, RenderedViewsGiveFocalLengthsWithinHalfAPercent) {
  const CalibrationBoard board(NineBySix());
  for (const Camera& truth : ThreeCameraRig()) {
    const std::vector<BoardObservation> views = RenderedViews(truth, board, 8, 11);
    ASSERT_GE(views.size(), 7u) << truth.name;
    std::vector<double> fractions;
    const IntrinsicsResult result = CalibrateIntrinsics(
        views, board, truth.width, truth.height, IntrinsicsOptions{},
        [&](double fraction, const std::string&) { fractions.push_back(fraction); });
    SCOPED_TRACE(truth.name);
    ExpectNearTruth(truth, result.camera);
    EXPECT_LT(result.rms_px, 0.15);
    EXPECT_EQ(result.UsedViews(), static_cast<int>(views.size()));
    EXPECT_EQ(result.camera.width, 640);
    EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
    ASSERT_FALSE(fractions.empty());
    EXPECT_EQ(fractions.back(), 1.0);
  }
}

TEST(IntrinsicsTest, AViewThatSpoilsTheFitIsFlaggedAndLeftOut) {
  const CalibrationBoard board(NineBySix());
  const Camera truth = ThreeCameraRig()[2];
  std::vector<BoardObservation> views = RenderedViews(truth, board, 8, 12);
  ASSERT_GE(views.size(), 7u);
  // A view whose corners are numbered wrongly (as a misdetection would).
  const size_t bad = 3;
  std::reverse(views[bad].pixels.begin() + 9, views[bad].pixels.begin() + 18);
  const IntrinsicsResult result =
      CalibrateIntrinsics(views, board, truth.width, truth.height, IntrinsicsOptions{});
  for (size_t i = 0; i < views.size(); ++i) EXPECT_EQ(result.views[i].used, i != bad) << i;
  EXPECT_GT(result.views[bad].rms_px, 10.0 * result.rms_px);
  EXPECT_EQ(result.views[bad].reprojected.size(), views[bad].size());
  ExpectNearTruth(truth, result.camera, 1.5);  // from one view fewer
}

TEST(IntrinsicsTest, TooFewViewsAreAnInputError) {
  const CalibrationBoard board(NineBySix());
  const std::vector<BoardObservation> views = RenderedViews(ThreeCameraRig()[0], board, 2, 13);
  EXPECT_THROW(CalibrateIntrinsics(views, board, 640, 480, IntrinsicsOptions{}), InputError);
  IntrinsicsOptions bad;
  bad.outlier_factor = 0.5;
  EXPECT_NE(bad.Validate().find("outlier_factor:"), std::string::npos);
}

struct OpenCvCalibration {
  double rms_px = 0.0;
  double fx = 0.0;
  double fy = 0.0;
};

OpenCvCalibration CalibrateWithOpenCv(const std::vector<std::vector<cv::Point2f>>& corners,
                                      cv::Size image_size) {
  std::vector<cv::Point3f> board;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 9; ++c) board.emplace_back(25.0f * c, 25.0f * r, 0.0f);
  }
  const std::vector<std::vector<cv::Point3f>> object(corners.size(), board);
  cv::Mat k, distortion, rvecs, tvecs;
  OpenCvCalibration out;
  out.rms_px = cv::calibrateCamera(object, corners, image_size, k, distortion, rvecs, tvecs);
  out.fx = k.at<double>(0, 0);
  out.fy = k.at<double>(1, 1);
  return out;
}

// The corners as OpenCV's calibration sample finds them (its default window
// of 23 x 23 px for cornerSubPix).
std::vector<cv::Point2f> OpenCvSampleCorners(const cv::Mat& image) {
  std::vector<cv::Point2f> corners;
  EXPECT_TRUE(cv::findChessboardCorners(
      image, cv::Size(9, 6), corners,
      cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_FAST_CHECK | cv::CALIB_CB_NORMALIZE_IMAGE));
  cv::cornerSubPix(image, corners, cv::Size(11, 11), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 1e-4));
  return corners;
}

// The pictures must be there: deploy/install-deps.sh installs opencv-doc.
std::vector<cv::Mat> LoadSample(const std::string& side) {
  std::vector<cv::Mat> images;
  for (const std::string& number : OpenCvSampleNumbers()) {
    const std::filesystem::path path = OpenCvSampleDir() / (side + number + ".jpg");
    EXPECT_TRUE(std::filesystem::exists(path))
        << path << " is missing: install the package opencv-doc (deploy/install-deps.sh)";
    const cv::Mat image = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
    if (!image.empty()) images.push_back(image);
  }
  return images;
}

// On OpenCV's own pictures: the same RMS as OpenCV's calibrateCamera on the
// same views and corners (the solver, the per-view errors and the flagging
// agree with OpenCV's), and no worse than OpenCV's sample pipeline from the
// images (this detector's sub-pixel corners are at least as good).
TEST(IntrinsicsTest, OpenCvSamplePicturesMatchOpenCvsOwnCalibration) {
  const CalibrationBoard board(NineBySix());
  for (const std::string side : {"left", "right"}) {
    SCOPED_TRACE(side);
    const std::vector<cv::Mat> images = LoadSample(side);
    ASSERT_EQ(images.size(), 13u);
    std::vector<BoardObservation> views;
    std::vector<std::vector<cv::Point2f>> our_corners, sample_corners;
    for (const cv::Mat& image : images) {
      const std::optional<BoardObservation> seen = board.Detect(image);
      ASSERT_TRUE(seen.has_value());
      views.push_back(*seen);
      our_corners.emplace_back();
      for (const Vec2& p : seen->pixels) our_corners.back().emplace_back(p.x(), p.y());
      sample_corners.push_back(OpenCvSampleCorners(image));
    }
    const IntrinsicsResult result =
        CalibrateIntrinsics(views, board, images[0].cols, images[0].rows, IntrinsicsOptions{});
    ASSERT_EQ(result.UsedViews(), 13);  // none of OpenCV's pictures spoils the fit
    const OpenCvCalibration same = CalibrateWithOpenCv(our_corners, images[0].size());
    const OpenCvCalibration sample = CalibrateWithOpenCv(sample_corners, images[0].size());
    EXPECT_NEAR(result.rms_px / same.rms_px, 1.0, 0.05);
    EXPECT_NEAR(result.camera.camera_matrix(0, 0) / same.fx, 1.0, 1e-3);
    EXPECT_LT(result.rms_px, 1.05 * sample.rms_px);
    EXPECT_NEAR(result.camera.camera_matrix(0, 0) / sample.fx, 1.0, 0.01);
    EXPECT_NEAR(result.camera.camera_matrix(1, 1) / sample.fy, 1.0, 0.01);
    std::printf(
        "[ measured ] %s: RMS %.4f px (OpenCV on these corners %.4f, OpenCV's sample "
        "pipeline %.4f); fx %.2f (%.2f, %.2f)\n",
        side.c_str(), result.rms_px, same.rms_px, sample.rms_px, result.camera.camera_matrix(0, 0),
        same.fx, sample.fx);
  }
}

}  // namespace
}  // namespace shapesense
