#include "tests/support/service_test_options.h"

namespace shapesense::testing {

CarvingServiceOptions TestCarvingOptions() {
  CarvingServiceOptions options;
  options.rig = "(in memory)";
  options.backgrounds = "(in memory)";
  options.carving.voxel_size = kTestVoxelSize;
  options.assembly.timeout_ms = 5000;  // generous: sanitizer builds are slow
  options.silhouette_rate_hz = 0;
  // The tests feed faster than the worker; overload has its own test.
  options.queue_capacity = 64;
  return options;
}

ShapeServiceOptions TestShapeOptions() {
  ShapeServiceOptions options;
  options.rig = "(in memory)";
  options.pairing_timeout_ms = 20000;
  options.queue_capacity = 64;
  return options;
}

}  // namespace shapesense::testing
