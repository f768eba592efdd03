#include "libs/calibration/pose_math.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace shapesense::calibration_detail {

Pose3 PoseFromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat rotation;
  cv::Rodrigues(rvec, rotation);
  Mat3 r;
  cv::cv2eigen(rotation, r);
  Pose3 pose = Pose3::Identity();
  pose.linear() = r;
  cv::Mat t;
  tvec.convertTo(t, CV_64F);
  pose.translation() = Vec3(t.at<double>(0), t.at<double>(1), t.at<double>(2));
  return pose;
}

std::array<double, 6> PoseToParameters(const Pose3& pose) {
  const Eigen::AngleAxisd angle_axis(Mat3(pose.linear()));
  const Vec3 rotation = angle_axis.angle() * angle_axis.axis();
  const Vec3 t = pose.translation();
  return {rotation.x(), rotation.y(), rotation.z(), t.x(), t.y(), t.z()};
}

Pose3 PoseFromParameters(const double* parameters) {
  return PoseFromRotationVector(Vec3(parameters[0], parameters[1], parameters[2]),
                                Vec3(parameters[3], parameters[4], parameters[5]));
}

cv::Mat CameraMatrixToCv(const Camera& camera) {
  cv::Mat k;
  cv::eigen2cv(camera.camera_matrix, k);
  return k;
}

cv::Mat DistortionToCv(const Camera& camera) {
  cv::Mat d(1, 5, CV_64F);
  for (int i = 0; i < 5; ++i) d.at<double>(0, i) = camera.distortion[static_cast<size_t>(i)];
  return d;
}

std::vector<cv::Point3f> ToCvPoints(const std::vector<Vec3>& points) {
  std::vector<cv::Point3f> out;
  out.reserve(points.size());
  for (const Vec3& p : points) {
    out.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                     static_cast<float>(p.z()));
  }
  return out;
}

std::vector<cv::Point2f> ToCvPixels(const std::vector<Vec2>& pixels) {
  std::vector<cv::Point2f> out;
  out.reserve(pixels.size());
  for (const Vec2& p : pixels) {
    out.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
  }
  return out;
}

std::optional<Pose3> BoardPoseFromCorners(const Camera& camera, const CalibrationBoard& board,
                                          const BoardObservation& view) {
  const std::vector<cv::Point3f> object = ToCvPoints(board.CornerPoints(view.ids));
  const std::vector<cv::Point2f> image = ToCvPixels(view.pixels);
  const cv::Mat k = CameraMatrixToCv(camera);
  const cv::Mat d = DistortionToCv(camera);
  cv::Mat rvec, tvec;
  try {
    if (!cv::solvePnP(object, image, k, d, rvec, tvec, false, cv::SOLVEPNP_IPPE)) {
      return std::nullopt;
    }
    cv::solvePnPRefineLM(object, image, k, d, rvec, tvec);
  } catch (const cv::Exception&) {
    return std::nullopt;  // degenerate corners
  }
  return PoseFromRvecTvec(rvec, tvec);
}

std::vector<Vec2> ReprojectCorners(const Camera& camera, const CalibrationBoard& board,
                                   const BoardObservation& view, const Pose3& cam_from_board) {
  std::vector<Vec2> pixels;
  pixels.reserve(view.size());
  for (const int id : view.ids) {
    const Vec3 in_camera = cam_from_board * board.CornerPoint(id);
    // Behind the camera only for a wildly wrong pose; keep the count aligned.
    const double z = std::max(in_camera.z(), 1e-9);
    pixels.push_back(camera.DistortAndScale(Vec2(in_camera.x() / z, in_camera.y() / z)));
  }
  return pixels;
}

double RmsDistance(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  if (a.empty()) return 0.0;
  double sum = 0.0;
  for (size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]).squaredNorm();
  return std::sqrt(sum / static_cast<double>(a.size()));
}

std::vector<size_t> FindOutliers(const std::vector<double>& errors, double factor, double floor) {
  if (errors.empty()) return {};
  std::vector<double> sorted = errors;
  const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), middle, sorted.end());
  const double limit = std::max(factor * *middle, floor);
  std::vector<size_t> outliers;
  for (size_t i = 0; i < errors.size(); ++i) {
    if (errors[i] > limit) outliers.push_back(i);
  }
  std::sort(outliers.begin(), outliers.end(),
            [&](size_t a, size_t b) { return errors[a] > errors[b]; });
  return outliers;
}

}  // namespace shapesense::calibration_detail
