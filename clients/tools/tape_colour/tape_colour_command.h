#pragma once

// `shapesense tape-colour --image IMG --background BG [--config FILE]`
//
// Learns the tape's colour from a calibration image (the manipulator with
// its tape in view) and the same camera's background, with the silhouette
// options of the config's `silhouette` section (config/pipeline.yaml,
// config/carving_service.yaml; the defaults without one) and their tape
// colour as the prior window, and prints the learnt colour as YAML to paste
// into that section, with the pixels it was learnt from and how many of the
// silhouette's pixels it labels tape.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <ostream>

#include "libs/silhouette/tape_colour.h"

namespace shapesense {

struct TapeColourArgs {
  std::filesystem::path image;       // BGR (or grey) picture with the manipulator
  std::filesystem::path background;  // the same camera's background
  std::filesystem::path config;      // YAML with a `silhouette` section; empty: the defaults
};

// Learns and prints to `out`. Throws InputError naming the file, key or
// what the image lacks (libs/silhouette/tape_colour.h).
LearntTapeColour RunTapeColour(const TapeColourArgs& args, std::ostream& out);

// The YAML snippet RunTapeColour prints: comments with the counts, then
// `silhouette: tape:` with the learnt keys documented.
std::string FormatLearntTapeColour(const LearntTapeColour& learnt, const TapeColourArgs& args);

// Registers `shapesense tape-colour`.
void AddTapeColourCommand(CLI::App& app);

}  // namespace shapesense
