#pragma once

// `shapesense calibrate intrinsics | extrinsics | background | register`:
// thin commands over libs/calibration (see docs/calibration.md). Each is a
// testable RunCalibrateX(args, log) that reads the input, calls the library
// and writes its output only after everything succeeded (atomically, so a
// failure leaves no broken file). Bad input is an InputError naming the
// file, camera or option and what is wrong.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "clients/tools/calibrate/image_source.h"
#include "libs/calibration/calibration_board.h"
#include "libs/calibration/extrinsics.h"
#include "libs/calibration/intrinsics.h"
#include "libs/calibration/point_registration.h"
#include "libs/camera/camera.h"

namespace shapesense {

struct IntrinsicsArgs {
  std::filesystem::path images;  // folder of one camera's views of the board
  std::filesystem::path out;     // camera YAML
  std::string name;              // camera name in the file; empty: the out file's stem
  BoardOptions board;
  IntrinsicsOptions options;
  std::filesystem::path overlays;  // folder for overlay PNGs; empty: none
  bool progress = true;            // progress bars on a terminal
};

struct IntrinsicsReport {
  IntrinsicsResult result;
  std::vector<std::string> view_names;     // the images with the board, in result.views order
  std::vector<std::string> without_board;  // the images where it was not found
};

// Calibrates from the images of a folder and writes the camera YAML (the
// rig file's camera keys plus `reprojection_error`, px RMS).
IntrinsicsReport RunCalibrateIntrinsics(const IntrinsicsArgs& args, std::ostream& log);
// The same over any image source (args.images is then unused).
IntrinsicsReport RunCalibrateIntrinsicsFrom(ImageSource& source, const IntrinsicsArgs& args,
                                            std::ostream& log);

struct ExtrinsicsArgs {
  std::filesystem::path views;  // DIR/<camera>/<view file>, synchronised views
  // "name=intrinsics.yaml", one per camera folder.
  std::vector<std::string> intrinsics;
  BoardOptions board;
  ExtrinsicsOptions options;
  // CSV "corner,x,y,z" (mm): world positions of corners of the anchor view;
  // empty: the world is the anchor view's board.
  std::filesystem::path anchor_points;
  std::filesystem::path out;  // rig YAML
  Vec3 workspace_min = Vec3(-128.0, -128.0, 0.0);
  Vec3 workspace_max = Vec3(128.0, 128.0, 256.0);
  Vec3 base_point = Vec3::Zero();
  std::filesystem::path overlays;  // folder for overlay PNGs; empty: none
  bool progress = true;
};

struct ExtrinsicsReport {
  ExtrinsicsResult result;
  Rig rig;                              // as written
  std::vector<std::string> view_names;  // in result order
};

ExtrinsicsReport RunCalibrateExtrinsics(const ExtrinsicsArgs& args, std::ostream& log);
ExtrinsicsReport RunCalibrateExtrinsicsFrom(FrameSetSource& source, const ExtrinsicsArgs& args,
                                            std::ostream& log);

struct BackgroundArgs {
  std::filesystem::path frames;  // DIR/<camera>/<frames of the empty scene>
  std::filesystem::path out;     // writes <camera>.png into it
  bool progress = true;
};

struct BackgroundReport {
  std::vector<std::string> cameras;
  std::vector<int> frames;  // per camera
};

BackgroundReport RunCalibrateBackground(const BackgroundArgs& args, std::ostream& log);

struct RegisterArgs {
  std::filesystem::path reference;  // digitizer points, CSV, mm
  std::filesystem::path sensed;     // the same points as the system sensed them, CSV, mm
  std::filesystem::path out;        // folder: registration.yaml, registration.png, report.md
  RegistrationOptions options;
};

struct RegisterReport {
  PointRegistration registration;
  std::vector<std::string> point_names;  // as matched
};

RegisterReport RunCalibrateRegister(const RegisterArgs& args, std::ostream& log);

// The camera YAML of `intrinsics`: FormatCameraYaml's keys plus reprojection_error.
std::string FormatCalibratedCameraYaml(const Camera& camera, double reprojection_error_px);

// Registers `calibrate` and its four subcommands.
void AddCalibrateCommand(CLI::App& app);

}  // namespace shapesense
