// shapesense-controller: tendon control on the sensed shape (controller_command.h).
#include "services/controller/controller_command.h"

int main(int argc, char** argv) { return shapesense::ControllerMain(argc, argv); }
