// shapesense-estimate-dev: the estimate subcommand alone, for development;
// the real command is `shapesense estimate ...` (clients/tools/main.cc).

#include "clients/tools/estimate/estimate_command.h"

int main(int argc, char** argv) {
  CLI::App app("shapesense (estimate only, development build)");
  app.require_subcommand(1);
  shapesense::AddEstimateCommand(app);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
