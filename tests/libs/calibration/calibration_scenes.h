#pragma once

// Synthetic calibration scenes with exact truth, shared by the calibration
// tests and the calibrate command's tests: a three-camera rig of 640x480
// cameras looking at the origin from ~450 mm, and board poses a person
// calibrating it would take.

#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "libs/calibration/calibration_board.h"
#include "libs/camera/camera.h"

namespace shapesense::testing {

constexpr double kDegree = std::numbers::pi / 180.0;

inline double Uniform(std::mt19937& rng, double low, double high) {
  return std::uniform_real_distribution<double>(low, high)(rng);
}

// Rotation angle between two rotations, degrees.
inline double AngleBetweenDeg(const Mat3& a, const Mat3& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() / kDegree;
}

// cam_from_world of a camera at `center` looking at `target`, image y down
// towards world -z.
inline Pose3 LookAt(const Vec3& center, const Vec3& target) {
  const Vec3 forward = (target - center).normalized();
  const Vec3 right = forward.cross(Vec3::UnitZ()).normalized();
  const Vec3 down = forward.cross(right);
  Mat3 world_from_cam;
  world_from_cam << right, down, forward;
  Pose3 pose = Pose3::Identity();
  pose.linear() = world_from_cam.transpose();
  pose.translation() = -pose.linear() * center;
  return pose;
}

// Three 640x480 cameras 120 degrees apart at 55 degrees elevation, ~450 mm
// from the origin, aimed near it, each with its own lens and distortion.
inline std::vector<Camera> ThreeCameraRig(uint32_t seed = 7) {
  std::mt19937 rng(seed);
  std::vector<Camera> cameras;
  for (int i = 0; i < 3; ++i) {
    Camera camera;
    camera.name = "cam" + std::to_string(i);
    camera.width = 640;
    camera.height = 480;
    const double f = Uniform(rng, 680.0, 740.0);
    camera.camera_matrix << f, 0.0, Uniform(rng, 310.0, 330.0), 0.0, f * Uniform(rng, 0.998, 1.002),
        Uniform(rng, 230.0, 250.0), 0.0, 0.0, 1.0;
    camera.distortion = {Uniform(rng, -0.15, -0.05), Uniform(rng, 0.0, 0.08),
                         Uniform(rng, -1e-3, 1e-3), Uniform(rng, -1e-3, 1e-3), 0.0};
    const double azimuth = (120.0 * i + Uniform(rng, -10.0, 10.0)) * kDegree;
    const double elevation = Uniform(rng, 50.0, 60.0) * kDegree;
    const double distance = Uniform(rng, 430.0, 470.0);
    const Vec3 center =
        distance * Vec3(std::cos(elevation) * std::cos(azimuth),
                        std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    camera.cam_from_world = LookAt(center, Vec3(Uniform(rng, -15, 15), Uniform(rng, -15, 15), 0.0));
    cameras.push_back(camera);
  }
  return cameras;
}

// Whether every corner of the board projects into the image, `margin` px inside.
inline bool AllCornersVisible(const Camera& camera, const CalibrationBoard& board,
                              const Pose3& cam_from_board, double margin) {
  for (int id = 0; id < board.NumCorners(); ++id) {
    const Vec3 p = cam_from_board * board.CornerPoint(id);
    if (p.z() < 50.0) return false;
    const Vec2 pixel = camera.DistortAndScale(Vec2(p.x() / p.z(), p.y() / p.z()));
    if (pixel.x() < margin || pixel.y() < margin || pixel.x() > camera.width - 1 - margin ||
        pixel.y() > camera.height - 1 - margin) {
      return false;
    }
  }
  return true;
}

// The board frame's centre, mm.
inline Vec3 BoardCentre(const CalibrationBoard& board) {
  const BoardOptions& o = board.options();
  return Vec3((o.cols - 1) * o.square / 2.0, (o.rows - 1) * o.square / 2.0, 0.0);
}

// A board pose a person would hold in front of one camera for its
// intrinsics: 300-500 mm away, anywhere in the view, tilted up to 40 degrees,
// turned any way in its plane; the whole board in the image.
inline Pose3 IntrinsicsBoardPose(const Camera& camera, const CalibrationBoard& board,
                                 std::mt19937& rng) {
  for (;;) {
    const Vec3 axis = Vec3(Uniform(rng, -1, 1), Uniform(rng, -1, 1), 0.0).normalized();
    const Mat3 rotation =
        Eigen::AngleAxisd(Uniform(rng, 15.0, 40.0) * kDegree, axis) *
        Eigen::AngleAxisd(Uniform(rng, -180.0, 180.0) * kDegree, Vec3::UnitZ()).toRotationMatrix();
    const double depth = Uniform(rng, 300.0, 500.0);
    const Vec3 centre(Uniform(rng, -0.25, 0.25) * depth, Uniform(rng, -0.2, 0.2) * depth, depth);
    Pose3 cam_from_board = Pose3::Identity();
    cam_from_board.linear() = rotation;
    cam_from_board.translation() = centre - rotation * BoardCentre(board);
    if (AllCornersVisible(camera, board, cam_from_board, 8.0)) return cam_from_board;
  }
}

// world_from_board of a board lying near the origin, printed side up
// (towards the rig's cameras), tilted up to `tilt_deg` and turned any way
// about the vertical.
inline Pose3 RigBoardPose(const CalibrationBoard& board, std::mt19937& rng,
                          double tilt_deg = 15.0) {
  const Vec3 axis = Vec3(Uniform(rng, -1, 1), Uniform(rng, -1, 1), 0.0).normalized();
  Mat3 face_up = Vec3(1.0, -1.0, -1.0).asDiagonal();  // board z down, into the table
  const Mat3 rotation = Eigen::AngleAxisd(Uniform(rng, 0.0, tilt_deg) * kDegree, axis) *
                        Eigen::AngleAxisd(Uniform(rng, -180.0, 180.0) * kDegree, Vec3::UnitZ()) *
                        face_up;
  Pose3 world_from_board = Pose3::Identity();
  world_from_board.linear() = rotation;
  const Vec3 centre(Uniform(rng, -30, 30), Uniform(rng, -30, 30), Uniform(rng, -20, 20));
  world_from_board.translation() = centre - rotation * BoardCentre(board);
  return world_from_board;
}

// OpenCV's sample chessboard pictures (package opencv-doc): left01.jpg ...
// right14.jpg, 9x6 inner corners; there is no left10/right10 (OpenCV's own
// stereo sample, stereo_calib.xml, lists these 13 pairs).
inline std::filesystem::path OpenCvSampleDir() { return "/usr/share/doc/opencv-doc/examples/data"; }
inline std::vector<std::string> OpenCvSampleNumbers() {
  return {"01", "02", "03", "04", "05", "06", "07", "08", "09", "11", "12", "13", "14"};
}

}  // namespace shapesense::testing
