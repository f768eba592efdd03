#include "libs/calibration/intrinsics.h"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <sstream>
#include <stdexcept>

#include "libs/calibration/pose_math.h"
#include "libs/core/error.h"

namespace shapesense {
namespace {

using calibration_detail::BoardPoseFromCorners;
using calibration_detail::FindOutliers;
using calibration_detail::ReprojectCorners;
using calibration_detail::RmsDistance;

int CalibrationFlags(const IntrinsicsOptions& options) {
  int flags = 0;
  if (options.fix_k3) flags |= cv::CALIB_FIX_K3;
  if (options.zero_tangential) flags |= cv::CALIB_ZERO_TANGENT_DIST;
  if (options.fix_aspect_ratio) flags |= cv::CALIB_FIX_ASPECT_RATIO;
  if (options.fix_principal_point) flags |= cv::CALIB_FIX_PRINCIPAL_POINT;
  return flags;
}

// calibrateCamera over the used views; the camera and each used view's pose.
Camera CalibrateUsedViews(const std::vector<BoardObservation>& views,
                          const std::vector<ViewFit>& fits, const CalibrationBoard& board,
                          int width, int height, const IntrinsicsOptions& options) {
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  for (size_t i = 0; i < views.size(); ++i) {
    if (!fits[i].used) continue;
    object.push_back(calibration_detail::ToCvPoints(board.CornerPoints(views[i].ids)));
    image.push_back(calibration_detail::ToCvPixels(views[i].pixels));
  }
  cv::Mat k = cv::Mat::eye(3, 3, CV_64F), d, rvecs, tvecs;
  try {
    cv::calibrateCamera(object, image, cv::Size(width, height), k, d, rvecs, tvecs,
                        CalibrationFlags(options));
  } catch (const cv::Exception& e) {
    throw InputError("intrinsics: OpenCV could not calibrate from " +
                     std::to_string(object.size()) + " views (" + e.err +
                     "); take views with the board tilted in different directions");
  }
  Camera camera;
  camera.width = width;
  camera.height = height;
  cv::cv2eigen(k, camera.camera_matrix);
  for (int i = 0; i < 5; ++i) camera.distortion[static_cast<size_t>(i)] = d.at<double>(i);
  return camera;
}

// Every view's pose and error under `camera`; a view OpenCV finds no pose for
// keeps a huge error so that it is flagged.
void FitViews(const Camera& camera, const std::vector<BoardObservation>& views,
              const CalibrationBoard& board, std::vector<ViewFit>* fits) {
  for (size_t i = 0; i < views.size(); ++i) {
    ViewFit& fit = (*fits)[i];
    const std::optional<Pose3> pose = BoardPoseFromCorners(camera, board, views[i]);
    fit.cam_from_board = pose.value_or(Pose3::Identity());
    fit.reprojected = ReprojectCorners(camera, board, views[i], fit.cam_from_board);
    fit.rms_px = pose ? RmsDistance(fit.reprojected, views[i].pixels) : 1e9;
  }
}

double UsedRms(const std::vector<BoardObservation>& views, const std::vector<ViewFit>& fits) {
  double sum = 0.0;
  size_t count = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    if (!fits[i].used) continue;
    sum += fits[i].rms_px * fits[i].rms_px * static_cast<double>(views[i].size());
    count += views[i].size();
  }
  return count > 0 ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
}

// The used view that most spoils the fit, if any may still be left out.
std::optional<size_t> WorstOutlier(const std::vector<ViewFit>& fits,
                                   const IntrinsicsOptions& options) {
  std::vector<double> errors;
  std::vector<size_t> index;
  for (size_t i = 0; i < fits.size(); ++i) {
    if (!fits[i].used) continue;
    errors.push_back(fits[i].rms_px);
    index.push_back(i);
  }
  if (static_cast<int>(errors.size()) <= options.min_views) return std::nullopt;
  const std::vector<size_t> outliers =
      FindOutliers(errors, options.outlier_factor, options.outlier_floor_px);
  if (outliers.empty()) return std::nullopt;
  return index[outliers.front()];
}

}  // namespace

std::string IntrinsicsOptions::Validate() const {
  std::ostringstream error;
  if (!std::isfinite(outlier_factor) || outlier_factor <= 1.0) {
    error << "outlier_factor: expected a number above 1, got " << outlier_factor;
  } else if (!std::isfinite(outlier_floor_px) || outlier_floor_px < 0.0) {
    error << "outlier_floor_px: expected a number >= 0, got " << outlier_floor_px;
  } else if (min_views < 3) {
    error << "min_views: expected at least 3, got " << min_views;
  }
  return error.str();
}

int IntrinsicsResult::UsedViews() const {
  int used = 0;
  for (const ViewFit& view : views) used += view.used ? 1 : 0;
  return used;
}

IntrinsicsResult CalibrateIntrinsics(const std::vector<BoardObservation>& views,
                                     const CalibrationBoard& board, int width, int height,
                                     const IntrinsicsOptions& options,
                                     const CalibrationProgress& progress) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("CalibrateIntrinsics: " + error);
  }
  if (static_cast<int>(views.size()) < options.min_views) {
    throw InputError("intrinsics: " + std::to_string(views.size()) + " views with the board (" +
                     board.Describe() + "); at least " + std::to_string(options.min_views) +
                     " are needed");
  }
  IntrinsicsResult result;
  result.views.resize(views.size());
  const size_t most_rounds = views.size() - static_cast<size_t>(options.min_views) + 1;
  for (size_t round = 0;; ++round) {
    if (progress) progress(static_cast<double>(round) / most_rounds, "calibrating");
    result.camera = CalibrateUsedViews(views, result.views, board, width, height, options);
    FitViews(result.camera, views, board, &result.views);
    const std::optional<size_t> worst = WorstOutlier(result.views, options);
    if (!worst) break;
    result.views[*worst].used = false;
  }
  result.rms_px = UsedRms(views, result.views);
  if (progress) progress(1.0, "calibrated");
  return result;
}

}  // namespace shapesense
