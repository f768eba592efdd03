// The command line of `shapesense calibrate`: options into args, args into RunCalibrateX.
#include "clients/tools/calibrate/calibrate_command.h"

#include <iostream>
#include <memory>
#include <sstream>

namespace shapesense {
namespace {

void AddBoardOptions(CLI::App* command, BoardOptions* board) {
  command->add_option("--pattern", board->pattern, "board: chessboard or charuco")
      ->check(CLI::IsMember({"chessboard", "charuco"}))
      ->capture_default_str();
  command->add_option("--cols", board->cols, "inner corners along a row (9 for 10x7 squares)")
      ->required();
  command->add_option("--rows", board->rows, "inner corners down a column (6 for 10x7 squares)")
      ->required();
  command->add_option("--square", board->square, "side of one square, mm")->required();
  command->add_option("--marker", board->marker,
                      "ChArUco: marker side, mm (default 0.75 x square)");
  command->add_option("--dictionary", board->dictionary, "ChArUco: OpenCV marker dictionary")
      ->capture_default_str();
}

// "x,y,z" in mm.
Vec3 ParseVec3(const std::string& text, const std::string& option) {
  std::stringstream stream(text);
  Vec3 value;
  char comma = 0;
  stream >> value.x() >> comma;
  const bool first = stream && comma == ',';
  stream >> value.y() >> comma;
  const bool second = stream && comma == ',';
  stream >> value.z();
  if (!first || !second || !stream || !(stream >> std::ws).eof()) {
    throw CLI::ValidationError(option, "expected x,y,z in mm, got '" + text + "'");
  }
  return value;
}

void AddVec3Option(CLI::App* command, const std::string& name, Vec3* value,
                   const std::string& help) {
  std::ostringstream fallback;
  fallback << value->x() << ',' << value->y() << ',' << value->z();
  command->add_option_function<std::string>(
      name, [value, name](const std::string& text) { *value = ParseVec3(text, name); },
      help + " (default " + fallback.str() + ")");
}

void AddIntrinsicsCommand(CLI::App& calibrate) {
  auto args = std::make_shared<IntrinsicsArgs>();
  CLI::App* command = calibrate.add_subcommand(
      "intrinsics", "A camera's intrinsics from views of a chessboard or ChArUco board");
  command->add_option("--images", args->images, "folder of the camera's views of the board")
      ->required();
  command->add_option("--out", args->out, "camera YAML to write (e.g. cam0.yaml)")->required();
  command->add_option("--name", args->name, "camera name in the file (default: --out's stem)");
  AddBoardOptions(command, &args->board);
  command->add_flag("--fix-k3", args->options.fix_k3, "hold k3 at 0");
  command->add_flag("--zero-tangential", args->options.zero_tangential, "hold p1 = p2 = 0");
  command->add_flag("--fix-aspect-ratio", args->options.fix_aspect_ratio, "hold fx = fy");
  command->add_flag("--fix-principal-point", args->options.fix_principal_point,
                    "hold the principal point at the image centre");
  command
      ->add_option("--outlier-factor", args->options.outlier_factor,
                   "leave out views above this times the median view's error")
      ->capture_default_str();
  command
      ->add_option("--outlier-floor", args->options.outlier_floor_px,
                   "... and above this error, px")
      ->capture_default_str();
  command->add_option("--overlays", args->overlays,
                      "folder for pictures of detected corners and reprojections");
  command->callback([args] { RunCalibrateIntrinsics(*args, std::cerr); });
}

void AddExtrinsicsCommand(CLI::App& calibrate) {
  auto args = std::make_shared<ExtrinsicsArgs>();
  CLI::App* command = calibrate.add_subcommand(
      "extrinsics", "The rig file from a board seen by several cameras at once");
  command
      ->add_option("--views", args->views,
                   "folder with one subfolder per camera of synchronised views (same file "
                   "names for the same instant)")
      ->required();
  command
      ->add_option("--intrinsics", args->intrinsics,
                   "CAMERA=FILE, a camera's YAML from `calibrate intrinsics`; one per camera")
      ->required();
  command->add_option("--out", args->out, "rig YAML to write (e.g. rig.yaml)")->required();
  AddBoardOptions(command, &args->board);
  command
      ->add_option("--anchor-view", args->options.anchor_view,
                   "index (from 0, in file-name order) of the view whose board is the world")
      ->capture_default_str();
  command->add_option("--anchor-points", args->anchor_points,
                      "CSV corner,x,y,z (mm): world positions of corners of the anchor view");
  command->add_flag("--refine-intrinsics", args->options.refine_intrinsics,
                    "refine the intrinsics with the poses");
  command->add_option("--loss-scale", args->options.loss_scale_px, "Huber loss scale, px (0: none)")
      ->capture_default_str();
  AddVec3Option(command, "--workspace-min", &args->workspace_min,
                "carving volume's low corner, mm");
  AddVec3Option(command, "--workspace-max", &args->workspace_max,
                "carving volume's high corner, mm");
  AddVec3Option(command, "--base-point", &args->base_point, "where the manipulator enters, mm");
  command->add_option("--overlays", args->overlays,
                      "folder for pictures of detected corners and reprojections");
  command->callback([args] { RunCalibrateExtrinsics(*args, std::cerr); });
}

void AddBackgroundCommand(CLI::App& calibrate) {
  auto args = std::make_shared<BackgroundArgs>();
  CLI::App* command = calibrate.add_subcommand(
      "background", "Each camera's background: the median of frames of the empty scene");
  command
      ->add_option("--frames", args->frames,
                   "folder with one subfolder per camera of frames of the empty scene")
      ->required();
  command
      ->add_option("--out", args->out,
                   "folder to write <camera>.png into (a dataset's background/)")
      ->required();
  command->callback([args] { RunCalibrateBackground(*args, std::cerr); });
}

void AddRegisterCommand(CLI::App& calibrate) {
  auto args = std::make_shared<RegisterArgs>();
  CLI::App* command = calibrate.add_subcommand(
      "register", "Rigid transform and error per axis against a reference digitizer");
  command
      ->add_option("--reference", args->reference, "digitizer points, CSV x,y,z or name,x,y,z, mm")
      ->required();
  command
      ->add_option("--sensed", args->sensed, "the same points as the system sensed them, CSV, mm")
      ->required();
  command->add_option("--out", args->out, "folder for report.md, registration.yaml and .png")
      ->required();
  command
      ->add_option("--loss-scale", args->options.loss_scale,
                   "Huber loss scale, mm (0: plain least squares)")
      ->capture_default_str();
  command->callback([args] { RunCalibrateRegister(*args, std::cerr); });
}

}  // namespace

void AddCalibrateCommand(CLI::App& app) {
  CLI::App* calibrate = app.add_subcommand(
      "calibrate",
      "Calibration tools: intrinsics, extrinsics, background, register (docs/calibration.md)");
  calibrate->require_subcommand(1);
  AddIntrinsicsCommand(*calibrate);
  AddExtrinsicsCommand(*calibrate);
  AddBackgroundCommand(*calibrate);
  AddRegisterCommand(*calibrate);
}

}  // namespace shapesense
