#pragma once

// The scene of a two-section manipulator in a configuration q
// (docs/mechanics.md): its centreline in the cameras' world, with the tape
// bands of its layout, so that the sensing side can measure the sections'
// lengths between them (libs/mechanics/configuration_sensing.h). The scene
// carries q, so its ground truth (TruthOf) does too.
//
// Tape layout, base → tip (rest distances, each band moving with its
// section's strain):
//   [a band `tapes.proximal_band_before_junction` before the junction,]
//   a band centred on the junction of the proximal and distal sections,
//   a band `tapes.distal_band_before_tip` before the tip.

#include <array>
#include <string>

#include "libs/geometry/types.h"
#include "libs/mechanics/configuration.h"
#include "libs/mechanics/configuration_sensing.h"
#include "libs/sim/tube_scene.h"

namespace shapesense {

struct ManipulatorSceneOptions {
  double radius = 3.0;  // tube radius, mm
  // The measured body starts this far from the base along the (straight)
  // proximal section, mm: where the cameras' volume begins for a proximal
  // section longer than the volume. What lies before it is drawn as the
  // straight lead-in. Beyond the junction, the body starts at the junction.
  double body_start = 0.0;
  double lead_in_length = 40.0;  // mm, drawn behind the body's start
  double spacing = 0.25;         // between centreline points, mm
  TapeLayout tapes;
  double band_width = 4.0;  // along the tube, mm
  std::array<double, 3> tape_bgr = {30.0, 30.0, 200.0};

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("radius", radius, "tube radius, mm (0.5-20)");
    visit("body_start", body_start,
          "distance from the base along the proximal section where the measured body starts, mm "
          "(>= 0; the lead-in stands for the part before)");
    visit("lead_in_length", lead_in_length, "straight lead-in drawn behind the body, mm (>= 0)");
    visit("spacing", spacing, "spacing of the centreline points, mm (0.01-0.5)");
    visit("tapes", tapes, "tape bands: at the junction, before the tip, optionally proximal");
    visit("band_width", band_width,
          "width of each band along the tube, mm (> 0; bands must not overlap)");
    visit("tape_bgr", tape_bgr, "tape colour, BGR 0-255");
  }
  std::string Validate() const;
};

// The scene of configuration q (rest lengths `rest`) with its base at
// `world_from_base`: the centreline from `body_start` to the tip in the world
// frame, the bands of the layout that lie on it, and q. Throws
// std::invalid_argument on options that fail Validate() or a geometry that
// fails ManipulatorGeometry::Validate() (bands beyond their sections).
TubeScene SceneOfConfiguration(const Configuration& q, const SectionLengths& rest,
                               const Pose3& world_from_base,
                               const ManipulatorSceneOptions& options);

}  // namespace shapesense
