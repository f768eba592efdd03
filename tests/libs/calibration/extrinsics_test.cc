// Extrinsics: a rendered three-camera rig with known truth (chessboard and
// ChArUco), the world anchor, input that cannot give a rig, and OpenCV's
// sample stereo pair against OpenCV's own stereoCalibrate.
#include "libs/calibration/extrinsics.h"

#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgcodecs.hpp>

#include "libs/calibration/intrinsics.h"
#include "libs/calibration/synthetic_board.h"
#include "libs/core/error.h"
#include "tests/libs/calibration/calibration_scenes.h"

namespace shapesense {
namespace {

using testing::AngleBetweenDeg;
using testing::RigBoardPose;
using testing::ThreeCameraRig;

BoardOptions RigChessboard() {
  BoardOptions options;
  options.cols = 9;
  options.rows = 6;
  options.square = 20.0;
  return options;
}

BoardOptions RigCharuco() {
  BoardOptions options;
  options.pattern = "charuco";
  options.cols = 7;
  options.rows = 5;
  options.square = 24.0;
  return options;
}

struct RenderedRig {
  std::vector<Camera> truth;
  std::vector<Pose3> world_from_board;  // per view
  ExtrinsicsInput input;                // intrinsics only; poses to be found
};

RenderedRig RenderRig(const CalibrationBoard& board, int views, uint32_t seed,
                      double tilt_deg = 15.0) {
  RenderedRig rig;
  rig.truth = ThreeCameraRig();
  std::mt19937 rng(seed);
  for (int v = 0; v < views; ++v) {
    rig.world_from_board.push_back(RigBoardPose(board, rng, tilt_deg));
    rig.input.view_names.push_back("view" + std::to_string(v));
  }
  for (const Camera& truth : rig.truth) {
    Camera intrinsics = truth;
    intrinsics.cam_from_world = Pose3::Identity();
    rig.input.cameras.push_back(intrinsics);
    rig.input.observations.emplace_back();
    const BoardViewRenderer renderer(truth);
    for (int v = 0; v < views; ++v) {
      BoardRenderOptions render;
      render.seed = seed + static_cast<uint32_t>(100 * rig.input.cameras.size() + v);
      const cv::Mat image = renderer.Render(
          board, truth.cam_from_world * rig.world_from_board[static_cast<size_t>(v)], render);
      rig.input.observations.back().push_back(board.Detect(image));
    }
  }
  return rig;
}

// The truth's world in the frame the result is anchored to by default: the
// anchor view's board, turned so that z leaves its printed side.
Pose3 TruthWorldFromAnchored(const RenderedRig& rig, int anchor) {
  Pose3 board_from_anchored = Pose3::Identity();
  board_from_anchored.linear() = Vec3(1.0, -1.0, -1.0).asDiagonal();
  return rig.world_from_board[static_cast<size_t>(anchor)] * board_from_anchored;
}

void ExpectPosesNearTruth(const RenderedRig& rig, const ExtrinsicsResult& result,
                          const Pose3& truth_world_from_result_world, double position_mm = 0.5,
                          double rotation_deg = 0.1) {
  for (size_t c = 0; c < rig.truth.size(); ++c) {
    SCOPED_TRACE(rig.truth[c].name);
    const Pose3 expected = rig.truth[c].cam_from_world * truth_world_from_result_world;
    const Pose3& got = result.cameras[c].cam_from_world;
    const double position_error =
        (got.inverse().translation() - expected.inverse().translation()).norm();
    const double rotation_error = AngleBetweenDeg(got.linear(), expected.linear());
    EXPECT_LT(position_error, position_mm);
    EXPECT_LT(rotation_error, rotation_deg);
    EXPECT_LT(result.camera_rms_px[c], 0.2);
    std::printf("[ measured ] %s: position %.3f mm, rotation %.4f deg, RMS %.3f px\n",
                rig.truth[c].name.c_str(), position_error, rotation_error, result.camera_rms_px[c]);
  }
}

TEST(ExtrinsicsTest, RenderedChessboardRigGivesPosesWithinHalfAMillimetre) {
  const CalibrationBoard board(RigChessboard());
  const RenderedRig rig = RenderRig(board, 5, 21);
  for (const auto& per_view : rig.input.observations) {
    ASSERT_EQ(
        std::count_if(per_view.begin(), per_view.end(), [](auto& o) { return o.has_value(); }), 5);
  }
  std::vector<double> fractions;
  ExtrinsicsOptions options;
  options.anchor_view = 2;
  const ExtrinsicsResult result = CalibrateExtrinsics(
      rig.input, board, options, [&](double f, const std::string&) { fractions.push_back(f); });
  ExpectPosesNearTruth(rig, result, TruthWorldFromAnchored(rig, 2));
  // The anchor view's board is the world: origin at corner 0, z out of its face.
  const Pose3& anchor = *result.world_from_board[2];
  EXPECT_LT(anchor.translation().norm(), 1e-9);
  EXPECT_LT(AngleBetweenDeg(anchor.linear(), Vec3(1.0, -1.0, -1.0).asDiagonal().toDenseMatrix()),
            1e-6);
  EXPECT_FALSE(fractions.empty());
  EXPECT_EQ(fractions.back(), 1.0);
}

TEST(ExtrinsicsTest, AnchorPointsPutTheRigInTheirFrame) {
  const CalibrationBoard board(RigChessboard());
  RenderedRig rig = RenderRig(board, 4, 22);
  for (const int corner : {0, 8, 45, 53, 22}) {
    rig.input.anchor_points.push_back(
        {corner, rig.world_from_board[1] * board.CornerPoint(corner)});
  }
  ExtrinsicsOptions options;
  options.anchor_view = 1;
  const ExtrinsicsResult result = CalibrateExtrinsics(rig.input, board, options);
  ExpectPosesNearTruth(rig, result, Pose3::Identity());
  EXPECT_LT(result.anchor_rms_mm, 0.2);
}

TEST(ExtrinsicsTest, RenderedCharucoRigGivesPosesWithinHalfAMillimetre) {
  const CalibrationBoard board(RigCharuco());
  const RenderedRig rig = RenderRig(board, 5, 23);
  const ExtrinsicsResult result = CalibrateExtrinsics(rig.input, board, ExtrinsicsOptions{});
  ExpectPosesNearTruth(rig, result, TruthWorldFromAnchored(rig, 0));
}

// Focal length trades off against distance unless the board is seen tilted
// in several directions: these views are tilted up to 30 degrees. Six views
// of a board in the middle fix the intrinsics less well than the
// `intrinsics` tool's views, so the poses get twice the tolerance.
TEST(ExtrinsicsTest, RefinesIntrinsicsThatStartOnePercentOff) {
  const CalibrationBoard board(RigChessboard());
  RenderedRig rig = RenderRig(board, 6, 24, 30.0);
  for (Camera& camera : rig.input.cameras) {
    camera.camera_matrix(0, 0) *= 1.01;
    camera.camera_matrix(1, 1) *= 0.99;
  }
  ExtrinsicsOptions options;
  options.refine_intrinsics = true;
  const ExtrinsicsResult result = CalibrateExtrinsics(rig.input, board, options);
  for (size_t c = 0; c < rig.truth.size(); ++c) {
    EXPECT_NEAR(result.cameras[c].camera_matrix(0, 0) / rig.truth[c].camera_matrix(0, 0), 1.0,
                0.005);
    EXPECT_NEAR(result.cameras[c].camera_matrix(1, 1) / rig.truth[c].camera_matrix(1, 1), 1.0,
                0.005);
  }
  ExpectPosesNearTruth(rig, result, TruthWorldFromAnchored(rig, 0), 1.0, 0.2);
}

// Error messages must name the camera or view and what is wrong.
void ExpectInputError(const ExtrinsicsInput& input, const CalibrationBoard& board,
                      const ExtrinsicsOptions& options, const std::string& expected) {
  try {
    CalibrateExtrinsics(input, board, options);
    ADD_FAILURE() << "expected an InputError with: " << expected;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
}

TEST(ExtrinsicsTest, InputThatCannotGiveARigIsAnInputErrorNamingTheCamera) {
  const CalibrationBoard board(RigChessboard());
  const RenderedRig rig = RenderRig(board, 3, 25);
  ExtrinsicsInput blind = rig.input;
  for (auto& view : blind.observations[1]) view.reset();
  ExpectInputError(blind, board, {}, "camera 'cam1': the board");

  ExtrinsicsInput unlinked = rig.input;  // cam2 sees only view 2, which nobody else sees
  for (size_t c = 0; c < 3; ++c) {
    for (size_t v = 0; v < 3; ++v) {
      if ((c == 2) != (v == 2)) unlinked.observations[c][v].reset();
    }
  }
  ExtrinsicsOptions anchor_0;
  ExpectInputError(unlinked, board, anchor_0, "camera 'cam2': shares no view");

  ExtrinsicsInput unseen_anchor = rig.input;
  for (auto& per_view : unseen_anchor.observations) per_view[1].reset();
  ExtrinsicsOptions anchor_1;
  anchor_1.anchor_view = 1;
  ExpectInputError(unseen_anchor, board, anchor_1, "anchor view 1 ('view1')");

  BoardOptions square = RigChessboard();
  square.cols = 7;
  square.rows = 7;
  ExpectInputError(rig.input, CalibrationBoard(square), {}, "turned by 180 degrees");

  ExtrinsicsInput too_few = rig.input;
  too_few.anchor_points = {{0, Vec3::Zero()}, {1, Vec3::UnitX()}};
  ExpectInputError(too_few, board, {}, "anchor points: expected at least 3");
}

std::vector<cv::Point2f> ToCvPixels(const BoardObservation& seen) {
  std::vector<cv::Point2f> pixels;
  for (const Vec2& p : seen.pixels) pixels.emplace_back(p.x(), p.y());
  return pixels;
}

// OpenCV's sample pair as an ExtrinsicsInput (cameras "left", "right" with
// their intrinsics from this library), and the corners as OpenCV takes them.
struct StereoSample {
  ExtrinsicsInput input;
  std::vector<std::vector<cv::Point2f>> pixels[2];
};

void LoadStereoSample(const CalibrationBoard& board, StereoSample* sample) {
  for (const std::string side : {"left", "right"}) {
    const size_t camera = sample->input.observations.size();
    sample->input.observations.emplace_back();
    std::vector<BoardObservation> views;
    for (const std::string& number : testing::OpenCvSampleNumbers()) {
      const auto path = testing::OpenCvSampleDir() / (side + number + ".jpg");
      const cv::Mat image = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
      ASSERT_FALSE(image.empty()) << path
                                  << " is missing: install opencv-doc (deploy/install-deps.sh)";
      const std::optional<BoardObservation> seen = board.Detect(image);
      ASSERT_TRUE(seen.has_value()) << path;
      sample->input.observations.back().push_back(seen);
      sample->pixels[camera].push_back(ToCvPixels(*seen));
      views.push_back(*seen);
      if (camera == 0) sample->input.view_names.push_back(number);
    }
    sample->input.cameras.push_back(CalibrateIntrinsics(views, board, 640, 480, {}).camera);
    sample->input.cameras.back().name = side;
  }
}

// right_from_left by OpenCV's stereoCalibrate with the intrinsics held.
Pose3 OpenCvStereoPose(const StereoSample& sample, const CalibrationBoard& board, double* rms) {
  std::vector<cv::Point3f> corners;
  for (int id = 0; id < board.NumCorners(); ++id) {
    const Vec3 p = board.CornerPoint(id);
    corners.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), 0.0f);
  }
  const std::vector<std::vector<cv::Point3f>> object(sample.pixels[0].size(), corners);
  cv::Mat k[2], d[2], r, t, e, f;
  for (size_t i = 0; i < 2; ++i) {
    cv::eigen2cv(sample.input.cameras[i].camera_matrix, k[i]);
    d[i] = cv::Mat(1, 5, CV_64F);
    for (int j = 0; j < 5; ++j) {
      d[i].at<double>(j) = sample.input.cameras[i].distortion[static_cast<size_t>(j)];
    }
  }
  *rms = cv::stereoCalibrate(object, sample.pixels[0], sample.pixels[1], k[0], d[0], k[1], d[1],
                             cv::Size(640, 480), r, t, e, f, cv::CALIB_FIX_INTRINSIC);
  Pose3 right_from_left = Pose3::Identity();
  Mat3 rotation;
  cv::cv2eigen(r, rotation);
  right_from_left.linear() = rotation;
  right_from_left.translation() = Vec3(t.at<double>(0), t.at<double>(1), t.at<double>(2));
  return right_from_left;
}

// OpenCV's sample stereo pair: the left-right pose against stereoCalibrate
// on the same corners with the same (fixed) intrinsics.
TEST(ExtrinsicsTest, OpenCvSampleStereoPairMatchesStereoCalibrate) {
  const CalibrationBoard board(BoardOptions{});  // 9 x 6; 25 mm stands in for the unknown square
  StereoSample sample;
  LoadStereoSample(board, &sample);
  ASSERT_FALSE(HasFatalFailure());
  const ExtrinsicsResult result = CalibrateExtrinsics(sample.input, board, ExtrinsicsOptions{});
  const Pose3 ours = result.cameras[1].cam_from_world * result.cameras[0].cam_from_world.inverse();
  double opencv_rms = 0.0;
  const Pose3 opencv = OpenCvStereoPose(sample, board, &opencv_rms);
  const double translation_difference =
      (ours.translation() - opencv.translation()).norm() / opencv.translation().norm();
  const double rotation_difference = AngleBetweenDeg(ours.linear(), opencv.linear());
  const double rotation_angle = Eigen::AngleAxisd(opencv.linear()).angle() / testing::kDegree;
  EXPECT_LT(translation_difference, 0.01);
  EXPECT_LT(rotation_difference, 0.01 * rotation_angle);
  std::printf(
      "[ measured ] stereo: baseline %.3f (OpenCV %.3f) squares, translation differs "
      "%.4f%%, rotation %.4f deg of %.3f deg; RMS %.3f px (OpenCV %.3f)\n",
      ours.translation().norm() / 25.0, opencv.translation().norm() / 25.0,
      100.0 * translation_difference, rotation_difference, rotation_angle, result.rms_px,
      opencv_rms);
}

}  // namespace
}  // namespace shapesense
