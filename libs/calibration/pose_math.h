#pragma once

// Small helpers shared by the calibration solvers (not part of the public API).

#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "libs/calibration/calibration_board.h"
#include "libs/camera/camera.h"

namespace shapesense::calibration_detail {

// OpenCV's rotation vector and translation <-> a pose.
Pose3 PoseFromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec);
// A pose as 6 numbers: angle-axis rotation, then translation (Ceres' layout).
std::array<double, 6> PoseToParameters(const Pose3& pose);
Pose3 PoseFromParameters(const double* parameters);

cv::Mat CameraMatrixToCv(const Camera& camera);
cv::Mat DistortionToCv(const Camera& camera);
std::vector<cv::Point3f> ToCvPoints(const std::vector<Vec3>& points);
std::vector<cv::Point2f> ToCvPixels(const std::vector<Vec2>& pixels);

// cam_from_board of a view from its corners, by planar PnP (IPPE) refined
// by Levenberg-Marquardt; nullopt when OpenCV finds no pose.
std::optional<Pose3> BoardPoseFromCorners(const Camera& camera, const CalibrationBoard& board,
                                          const BoardObservation& view);

// Pixels of the view's corners through the camera at cam_from_board, and
// their RMS distance from the detected corners.
std::vector<Vec2> ReprojectCorners(const Camera& camera, const CalibrationBoard& board,
                                   const BoardObservation& view, const Pose3& cam_from_board);
double RmsDistance(const std::vector<Vec2>& a, const std::vector<Vec2>& b);

// Indices whose error spoils a fit: above factor times the median of
// `errors` and above floor; worst first.
std::vector<size_t> FindOutliers(const std::vector<double>& errors, double factor, double floor);

}  // namespace shapesense::calibration_detail
