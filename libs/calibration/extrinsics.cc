#include "libs/calibration/extrinsics.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <array>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include "libs/calibration/point_registration.h"
#include "libs/calibration/pose_math.h"
#include "libs/core/error.h"

namespace shapesense {
namespace {

using calibration_detail::PoseFromParameters;
using calibration_detail::PoseToParameters;
using OptionalPoses = std::vector<std::optional<Pose3>>;
using UsedMask = std::vector<std::vector<bool>>;  // [camera][view]

// Intrinsics as Ceres sees them: fx fy cx cy k1 k2 p1 p2 k3 (skew held fixed).
using IntrinsicParameters = std::array<double, 9>;
using PoseParameters = std::array<double, 6>;

IntrinsicParameters ToParameters(const Camera& camera) {
  const Mat3& k = camera.camera_matrix;
  const auto& d = camera.distortion;
  return {k(0, 0), k(1, 1), k(0, 2), k(1, 2), d[0], d[1], d[2], d[3], d[4]};
}

void FromParameters(const IntrinsicParameters& p, Camera* camera) {
  Mat3& k = camera->camera_matrix;
  k(0, 0) = p[0];
  k(1, 1) = p[1];
  k(0, 2) = p[2];
  k(1, 2) = p[3];
  for (size_t i = 0; i < 5; ++i) camera->distortion[i] = p[4 + i];
}

// One board corner seen by one camera: the pixel Camera::Project would give
// for it, against the detected pixel.
struct CornerResidual {
  Vec2 observed;
  Vec3 board_point;
  double skew;

  template <class T>
  bool operator()(const T* cam_from_world, const T* world_from_board, const T* intrinsics,
                  T* residual) const {
    const T board[3] = {static_cast<T>(board_point.x()), static_cast<T>(board_point.y()),
                        static_cast<T>(board_point.z())};
    T world[3], camera[3];
    ceres::AngleAxisRotatePoint(world_from_board, board, world);
    for (int i = 0; i < 3; ++i) world[i] += world_from_board[3 + i];
    ceres::AngleAxisRotatePoint(cam_from_world, world, camera);
    for (int i = 0; i < 3; ++i) camera[i] += cam_from_world[3 + i];
    const T x = camera[0] / camera[2];
    const T y = camera[1] / camera[2];
    const T* d = intrinsics + 4;  // k1 k2 p1 p2 k3
    const T r2 = x * x + y * y;
    const T radial = 1.0 + r2 * (d[0] + r2 * (d[1] + r2 * d[4]));
    const T xd = x * radial + 2.0 * d[2] * x * y + d[3] * (r2 + 2.0 * x * x);
    const T yd = y * radial + d[2] * (r2 + 2.0 * y * y) + 2.0 * d[3] * x * y;
    residual[0] = intrinsics[0] * xd + skew * yd + intrinsics[2] - observed.x();
    residual[1] = intrinsics[1] * yd + intrinsics[3] - observed.y();
    return true;
  }
};

// Reports the solver's iterations as progress.
class IterationProgress : public ceres::IterationCallback {
 public:
  IterationProgress(const CalibrationProgress& progress, int max_iterations, std::string stage)
      : progress_(progress), max_iterations_(max_iterations), stage_(std::move(stage)) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (progress_) {
      progress_(std::min(1.0, static_cast<double>(summary.iteration) / max_iterations_), stage_);
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const CalibrationProgress& progress_;
  int max_iterations_;
  std::string stage_;
};

void CheckSizes(const ExtrinsicsInput& input, const ExtrinsicsOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("CalibrateExtrinsics: " + error);
  }
  if (input.cameras.empty() || input.observations.size() != input.cameras.size()) {
    throw std::invalid_argument("CalibrateExtrinsics: expected observations for every camera");
  }
  for (const auto& per_view : input.observations) {
    if (per_view.size() != input.view_names.size()) {
      throw std::invalid_argument("CalibrateExtrinsics: expected one entry per view per camera");
    }
  }
}

int CountSeen(const std::vector<std::optional<BoardObservation>>& views) {
  int seen = 0;
  for (const auto& view : views) seen += view ? 1 : 0;
  return seen;
}

void CheckAnchor(const ExtrinsicsInput& input, const CalibrationBoard& board, int anchor) {
  if (anchor >= static_cast<int>(input.view_names.size())) {
    throw InputError("anchor view: expected a view index below " +
                     std::to_string(input.view_names.size()) + ", got " + std::to_string(anchor));
  }
  bool seen = false;
  for (const auto& per_view : input.observations) {
    seen |= per_view[static_cast<size_t>(anchor)].has_value();
  }
  if (!seen) {
    throw InputError("anchor view " + std::to_string(anchor) + " ('" +
                     input.view_names[static_cast<size_t>(anchor)] +
                     "'): no camera found the board in it; choose another view");
  }
  if (!input.anchor_points.empty() && input.anchor_points.size() < 3) {
    throw InputError("anchor points: expected at least 3, got " +
                     std::to_string(input.anchor_points.size()));
  }
  for (const AnchorPoint& point : input.anchor_points) {
    if (point.corner < 0 || point.corner >= board.NumCorners()) {
      throw InputError("anchor points: corner " + std::to_string(point.corner) +
                       " is not on the board (0-" + std::to_string(board.NumCorners() - 1) + ")");
    }
  }
}

void CheckInput(const ExtrinsicsInput& input, const CalibrationBoard& board,
                const ExtrinsicsOptions& options) {
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    if (CountSeen(input.observations[c]) == 0) {
      throw InputError("camera '" + input.cameras[c].name + "': the board (" + board.Describe() +
                       ") was not found in any of its " + std::to_string(input.view_names.size()) +
                       " views");
    }
  }
  if (input.cameras.size() > 1 && !board.IsOrientationUnambiguous()) {
    throw InputError("board: a " + board.Describe() +
                     " looks the same turned by 180 degrees, so cameras could number its corners "
                     "differently; use one with cols + rows odd (e.g. 9x6) or a ChArUco board");
  }
  CheckAnchor(input, board, options.anchor_view);
}

// Each observation's cam_from_board by PnP; an observation PnP fails on is dropped.
std::vector<OptionalPoses> PnpPoses(const ExtrinsicsInput& input, const CalibrationBoard& board) {
  std::vector<OptionalPoses> poses(input.cameras.size());
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    int found = 0;
    for (const auto& view : input.observations[c]) {
      poses[c].push_back(
          view ? calibration_detail::BoardPoseFromCorners(input.cameras[c], board, *view)
               : std::nullopt);
      found += poses[c].back() ? 1 : 0;
    }
    if (found == 0) {
      throw InputError("camera '" + input.cameras[c].name +
                       "': no board pose could be found from its corners in any view; check its "
                       "intrinsics and the board's size");
    }
  }
  return poses;
}

struct ChainedPoses {
  OptionalPoses cam_from_world;  // world = camera 0 until anchored
  OptionalPoses world_from_board;
};

// Spreads known poses through shared views until nothing changes.
bool ChainOnce(const std::vector<OptionalPoses>& pnp, ChainedPoses* poses) {
  bool changed = false;
  for (size_t c = 0; c < pnp.size(); ++c) {
    for (size_t v = 0; v < pnp[c].size(); ++v) {
      if (!pnp[c][v]) continue;
      auto& camera = poses->cam_from_world[c];
      auto& board = poses->world_from_board[v];
      if (camera && !board) {
        board = camera->inverse() * *pnp[c][v];
        changed = true;
      } else if (!camera && board) {
        camera = *pnp[c][v] * board->inverse();
        changed = true;
      }
    }
  }
  return changed;
}

ChainedPoses ChainPoses(const ExtrinsicsInput& input, const std::vector<OptionalPoses>& pnp) {
  ChainedPoses poses;
  poses.cam_from_world.resize(input.cameras.size());
  poses.world_from_board.resize(input.view_names.size());
  poses.cam_from_world[0] = Pose3::Identity();
  while (ChainOnce(pnp, &poses)) {
  }
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    if (!poses.cam_from_world[c]) {
      throw InputError("camera '" + input.cameras[c].name +
                       "': shares no view of the board with camera '" + input.cameras[0].name +
                       "', directly or through other cameras; take views that both see");
    }
  }
  return poses;
}

// The joint problem's parameters.
struct JointState {
  std::vector<PoseParameters> cam_from_world;
  std::vector<PoseParameters> world_from_board;  // zeros for views no camera saw
  std::vector<IntrinsicParameters> intrinsics;
  std::vector<Camera> cameras;  // the above as cameras (world = camera 0 until anchored)
  OptionalPoses world_from_board_poses;

  void UpdateCameras() {
    for (size_t c = 0; c < cameras.size(); ++c) {
      cameras[c].cam_from_world = PoseFromParameters(cam_from_world[c].data());
      FromParameters(intrinsics[c], &cameras[c]);
    }
    for (size_t v = 0; v < world_from_board.size(); ++v) {
      if (world_from_board_poses[v]) {
        world_from_board_poses[v] = PoseFromParameters(world_from_board[v].data());
      }
    }
  }
};

JointState InitialState(const ExtrinsicsInput& input, const ChainedPoses& poses) {
  JointState state;
  state.cameras = input.cameras;
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    state.cam_from_world.push_back(PoseToParameters(*poses.cam_from_world[c]));
    state.intrinsics.push_back(ToParameters(input.cameras[c]));
  }
  for (const auto& pose : poses.world_from_board) {
    state.world_from_board.push_back(pose ? PoseToParameters(*pose) : PoseParameters{});
  }
  state.world_from_board_poses = poses.world_from_board;
  state.UpdateCameras();
  return state;
}

ceres::Solver::Summary SolveJointly(const ExtrinsicsInput& input, const CalibrationBoard& board,
                                    const ExtrinsicsOptions& options, const UsedMask& used,
                                    const CalibrationProgress& progress, JointState* state) {
  ceres::Problem problem;
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    for (size_t v = 0; v < input.view_names.size(); ++v) {
      if (!used[c][v]) continue;
      const BoardObservation& view = *input.observations[c][v];
      for (size_t i = 0; i < view.size(); ++i) {
        auto* cost = new ceres::AutoDiffCostFunction<CornerResidual, 2, 6, 6, 9>(new CornerResidual{
            view.pixels[i], board.CornerPoint(view.ids[i]), input.cameras[c].camera_matrix(0, 1)});
        ceres::LossFunction* loss =
            options.loss_scale_px > 0.0 ? new ceres::HuberLoss(options.loss_scale_px) : nullptr;
        problem.AddResidualBlock(cost, loss, state->cam_from_world[c].data(),
                                 state->world_from_board[v].data(), state->intrinsics[c].data());
      }
    }
  }
  problem.SetParameterBlockConstant(state->cam_from_world[0].data());  // fixes the gauge
  for (auto& intrinsics : state->intrinsics) {
    if (!options.refine_intrinsics) problem.SetParameterBlockConstant(intrinsics.data());
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-12;
  solver.num_threads = 1;
  IterationProgress callback(progress, options.max_iterations, "bundle adjustment");
  solver.callbacks.push_back(&callback);
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  state->UpdateCameras();
  return summary;
}

std::vector<std::vector<std::optional<ObservationFit>>> FitObservations(
    const ExtrinsicsInput& input, const CalibrationBoard& board, const JointState& state,
    const UsedMask& used) {
  std::vector<std::vector<std::optional<ObservationFit>>> fits(input.cameras.size());
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    for (size_t v = 0; v < input.view_names.size(); ++v) {
      const auto& view = input.observations[c][v];
      if (!view || !state.world_from_board_poses[v]) {
        fits[c].emplace_back();
        continue;
      }
      const Pose3 cam_from_board =
          state.cameras[c].cam_from_world * *state.world_from_board_poses[v];
      ObservationFit fit;
      fit.used = used[c][v];
      fit.reprojected =
          calibration_detail::ReprojectCorners(state.cameras[c], board, *view, cam_from_board);
      fit.rms_px = calibration_detail::RmsDistance(fit.reprojected, view->pixels);
      fits[c].push_back(fit);
    }
  }
  return fits;
}

// Leaves out the observations that spoil the fit, keeping at least one per
// camera and one of the anchor view; whether any was left out.
bool LeaveOutOutliers(const std::vector<std::vector<std::optional<ObservationFit>>>& fits,
                      const ExtrinsicsOptions& options, UsedMask* used) {
  std::vector<double> errors;
  std::vector<std::pair<size_t, size_t>> where;
  for (size_t c = 0; c < fits.size(); ++c) {
    for (size_t v = 0; v < fits[c].size(); ++v) {
      if (!fits[c][v] || !(*used)[c][v]) continue;
      errors.push_back(fits[c][v]->rms_px);
      where.emplace_back(c, v);
    }
  }
  bool changed = false;
  for (const size_t i :
       calibration_detail::FindOutliers(errors, options.outlier_factor, options.outlier_floor_px)) {
    const auto [c, v] = where[i];
    int camera_left = 0, anchor_left = 0;
    for (const bool u : (*used)[c]) camera_left += u ? 1 : 0;
    for (const auto& per_view : *used) {
      anchor_left += per_view[static_cast<size_t>(options.anchor_view)] ? 1 : 0;
    }
    if (camera_left <= 1 || (static_cast<int>(v) == options.anchor_view && anchor_left <= 1)) {
      continue;
    }
    (*used)[c][v] = false;
    changed = true;
  }
  return changed;
}

// world (as anchored) from the solver's world (camera 0).
Pose3 AnchoredFromSolverWorld(const ExtrinsicsInput& input, const CalibrationBoard& board,
                              const ExtrinsicsOptions& options, const JointState& state,
                              double* anchor_rms_mm) {
  const auto& anchor_pose = state.world_from_board_poses[static_cast<size_t>(options.anchor_view)];
  if (!anchor_pose) {
    throw InputError("anchor view " + std::to_string(options.anchor_view) +
                     ": no board pose could be found in it; choose another view");
  }
  const Pose3 world_from_anchor_board = *anchor_pose;
  if (input.anchor_points.empty()) {
    // The board frame turned by 180 degrees about x: z out of the printed side.
    Pose3 anchored_from_board = Pose3::Identity();
    anchored_from_board.linear() = Vec3(1.0, -1.0, -1.0).asDiagonal();
    return anchored_from_board * world_from_anchor_board.inverse();
  }
  std::vector<Vec3> solver_points, anchored_points;
  for (const AnchorPoint& point : input.anchor_points) {
    solver_points.push_back(world_from_anchor_board * board.CornerPoint(point.corner));
    anchored_points.push_back(point.world);
  }
  const PointRegistration fit = RegisterPoints(solver_points, anchored_points);
  *anchor_rms_mm = fit.rms;
  return fit.reference_from_sensed;
}

void ApplyAnchor(const Pose3& anchored_from_solver, ExtrinsicsResult* result) {
  for (Camera& camera : result->cameras) {
    camera.cam_from_world = camera.cam_from_world * anchored_from_solver.inverse();
  }
  for (auto& pose : result->world_from_board) {
    if (pose) pose = anchored_from_solver * *pose;
  }
}

void SummariseErrors(const ExtrinsicsInput& input, ExtrinsicsResult* result) {
  double total = 0.0;
  size_t total_count = 0;
  for (size_t c = 0; c < result->fits.size(); ++c) {
    double sum = 0.0;
    size_t count = 0;
    for (size_t v = 0; v < result->fits[c].size(); ++v) {
      const auto& fit = result->fits[c][v];
      if (!fit || !fit->used) continue;
      const size_t n = input.observations[c][v]->size();
      sum += fit->rms_px * fit->rms_px * static_cast<double>(n);
      count += n;
    }
    result->camera_rms_px.push_back(count > 0 ? std::sqrt(sum / static_cast<double>(count)) : 0.0);
    total += sum;
    total_count += count;
  }
  result->rms_px = total_count > 0 ? std::sqrt(total / static_cast<double>(total_count)) : 0.0;
}

}  // namespace

std::string ExtrinsicsOptions::Validate() const {
  std::ostringstream error;
  if (anchor_view < 0) {
    error << "anchor_view: expected a view index >= 0, got " << anchor_view;
  } else if (!std::isfinite(loss_scale_px) || loss_scale_px < 0.0) {
    error << "loss_scale_px: expected a number >= 0, got " << loss_scale_px;
  } else if (max_iterations <= 0) {
    error << "max_iterations: expected a positive number, got " << max_iterations;
  } else if (!std::isfinite(outlier_factor) || outlier_factor <= 1.0) {
    error << "outlier_factor: expected a number above 1, got " << outlier_factor;
  } else if (!std::isfinite(outlier_floor_px) || outlier_floor_px < 0.0) {
    error << "outlier_floor_px: expected a number >= 0, got " << outlier_floor_px;
  }
  return error.str();
}

ExtrinsicsResult CalibrateExtrinsics(const ExtrinsicsInput& input, const CalibrationBoard& board,
                                     const ExtrinsicsOptions& options,
                                     const CalibrationProgress& progress) {
  CheckSizes(input, options);
  CheckInput(input, board, options);
  const std::vector<OptionalPoses> pnp = PnpPoses(input, board);
  JointState state = InitialState(input, ChainPoses(input, pnp));
  UsedMask used(input.cameras.size());
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    for (const auto& pose : pnp[c]) used[c].push_back(pose.has_value());
  }
  ExtrinsicsResult result;
  constexpr int kMaxRounds = 4;  // of leaving out outliers and solving again
  for (int round = 0; round < kMaxRounds; ++round) {
    const ceres::Solver::Summary summary =
        SolveJointly(input, board, options, used, progress, &state);
    result.iterations = static_cast<int>(summary.iterations.size());
    result.solver_report = summary.BriefReport();
    result.fits = FitObservations(input, board, state, used);
    if (!LeaveOutOutliers(result.fits, options, &used)) break;
  }
  result.cameras = state.cameras;
  result.world_from_board = state.world_from_board_poses;
  ApplyAnchor(AnchoredFromSolverWorld(input, board, options, state, &result.anchor_rms_mm),
              &result);
  SummariseErrors(input, &result);
  if (progress) progress(1.0, "bundle adjustment");
  return result;
}

}  // namespace shapesense
