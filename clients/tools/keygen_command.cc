#include "clients/tools/keygen_command.h"

#include <iostream>
#include <memory>

#include "runtime/security/key_file.h"

namespace shapesense {

uint32_t RunKeygen(const std::filesystem::path& out, uint32_t id, std::ostream& log) {
  if (id == 0) id = KeyIdFromClock();
  WriteKeyFile(out, NewAuthKey(id));
  log << "wrote key " << id << " to " << out.string()
      << " (mode 0600); copy it to the rig's hosts over a secure channel (docs/security.md)\n";
  return id;
}

void AddKeygenCommand(CLI::App& app) {
  struct Args {
    std::filesystem::path out;
    uint32_t id = 0;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command = app.add_subcommand(
      "keygen", "A new 256-bit key for the messages that move the robot (docs/security.md)");
  command->add_option("--out", args->out, "the key file to create (never overwritten)")->required();
  command->add_option("--id", args->id, "its key id (default: the time in seconds)");
  command->callback([args] { RunKeygen(args->out, args->id, std::cout); });
}

}  // namespace shapesense
