// shapesense-shape: voxel clouds (and their images) → shapes, over LCM (see shape_service.h).
#include "runtime/lcm/service_main.h"
#include "services/shape/shape_service.h"

int main(int argc, char** argv) {
  return shapesense::ServiceMain(argc, argv, "shapesense-shape",
                                 "voxel clouds (and their images) → shapes, over LCM",
                                 "config/shape_service.yaml", shapesense::RunShapeService);
}
