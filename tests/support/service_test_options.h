#pragma once

// The carving and shape services' options for tests: the in-memory rig of
// TestRig, a coarse voxel size, and generous timeouts and queues.
#include "services/carving/carving_service.h"
#include "services/shape/shape_service.h"

namespace shapesense::testing {

// Voxel size of the service tests, mm: 2 mm keeps the table at 25 MB and
// its build well under a second even under the sanitizers; the refinement
// against the silhouettes still measures to a fraction of a millimetre.
inline constexpr double kTestVoxelSize = 2.0;

CarvingServiceOptions TestCarvingOptions();
ShapeServiceOptions TestShapeOptions();

}  // namespace shapesense::testing
