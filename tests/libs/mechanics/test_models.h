#pragma once

// Manipulator models for the tests: the example catheter of
// config/manipulator.yaml and random layouts and stiffnesses.

#include <cmath>
#include <numbers>
#include <random>

#include "libs/mechanics/manipulator_options.h"

namespace shapesense::testing {

// Four tendons at 90 degrees, 1.2 mm from the axis; 160 mm distal section.
inline ManipulatorOptions CatheterOptions() {
  ManipulatorOptions options;
  options.proximal_length = 600.0;
  options.distal_length = 160.0;
  for (int i = 0; i < 4; ++i) {
    const double angle = i * std::numbers::pi / 2.0;
    options.tendons.push_back({1.2 * std::cos(angle), 1.2 * std::sin(angle), 900.0, 6000.0});
  }
  options.stiffness = {400.0, 400.0, 2500.0, 800.0};
  return options;
}

inline double LogUniform(std::mt19937_64& rng, double low, double high) {
  std::uniform_real_distribution<double> u(std::log(low), std::log(high));
  return std::exp(u(rng));
}

// 3 to 8 tendons at random angles (the layout always valid: no gap of pi or
// more) and radii, random lengths and stiffnesses over realistic ranges.
inline ManipulatorOptions RandomOptions(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> count(3, 8);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  std::uniform_real_distribution<double> radius(0.5, 3.0);
  ManipulatorOptions options;
  options.proximal_length = LogUniform(rng, 100.0, 1000.0);
  options.distal_length = LogUniform(rng, 50.0, 250.0);
  do {
    options.tendons.clear();
    const int n = count(rng);
    for (int i = 0; i < n; ++i) {
      const double a = angle(rng), r = radius(rng);
      const double length =
          options.proximal_length + options.distal_length + LogUniform(rng, 10.0, 500.0);
      options.tendons.push_back(
          {r * std::cos(a), r * std::sin(a), length, LogUniform(rng, 2000.0, 20000.0)});
    }
  } while (TendonLayoutGap(options.tendons) > std::numbers::pi - 0.2);
  options.stiffness = {LogUniform(rng, 100.0, 2000.0), LogUniform(rng, 100.0, 2000.0),
                       LogUniform(rng, 300.0, 5000.0), LogUniform(rng, 300.0, 5000.0)};
  return options;
}

}  // namespace shapesense::testing
