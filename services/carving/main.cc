// shapesense-carving: camera images → voxel clouds, over LCM (see carving_service.h).
#include "runtime/lcm/service_main.h"
#include "services/carving/carving_service.h"

int main(int argc, char** argv) {
  return shapesense::ServiceMain(argc, argv, "shapesense-carving",
                                 "frame-sets of camera images → voxel clouds, over LCM",
                                 "config/carving_service.yaml", shapesense::RunCarvingService);
}
