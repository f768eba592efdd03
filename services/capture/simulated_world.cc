#include "services/capture/simulated_world.h"

#include <stdexcept>

namespace shapesense {
namespace {

// splitmix64: well-mixed bits from a counter.
uint64_t Mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace

std::string SimulationOptions::Validate() const {
  if (const std::string error = trajectory.Validate(); !error.empty()) return "trajectory." + error;
  return "";
}

SimulatedWorld::SimulatedWorld(Rig rig, SimulationOptions options, int64_t origin_utime)
    : rig_(std::move(rig)), options_(std::move(options)), origin_utime_(origin_utime) {
  if (const std::string error = options_.Validate(); !error.empty()) {
    throw std::invalid_argument("simulation: " + error);
  }
  if (const std::string error = rig_.Validate(); !error.empty()) {
    throw std::invalid_argument("rig: " + error);
  }
}

uint32_t SimulatedWorld::ViewSeed(int64_t frame, size_t camera_index) const {
  const uint64_t key =
      Mix(Mix(options_.seed) ^ static_cast<uint64_t>(frame)) ^ Mix(camera_index + 1);
  return static_cast<uint32_t>(Mix(key) >> 32);
}

}  // namespace shapesense
