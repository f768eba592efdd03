// shapesense-actuator-sim: a simulated serial tendon actuator on a new
// pseudo-terminal (docs/actuators.md), for trying the serial driver or the
// protocol by hand; or simulated CiA 402 drives on a SocketCAN interface.
//
//   shapesense-actuator-sim [--axes 4] [--speed 50] [--travel 50] [--link /tmp/actuator]
//   shapesense-actuator-sim --can vcan0 --nodes 1,2,3,4
//
// Prints where it serves, then serves until SIGINT or SIGTERM.
#include <CLI/CLI.hpp>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <vector>

#include "libs/core/error.h"
#include "runtime/command_line.h"
#include "runtime/devices/serial_port.h"
#include "runtime/devices/socketcan_bus.h"
#include "services/rig_sim/actuators/simulated_cia402_drive.h"
#include "services/rig_sim/actuators/simulated_serial_actuator.h"

namespace shapesense {
namespace {

struct SimArguments {
  SimulatedSerialActuatorOptions serial;
  std::string link;
  std::string can_interface;
  std::vector<int> nodes = {1, 2, 3, 4};
};

// Blocks SIGINT and SIGTERM in every thread and waits for one here.
void WaitForTermination(const sigset_t& signals) {
  int received = 0;
  sigwait(&signals, &received);
}

int ServeSerial(const SimArguments& arguments, const sigset_t& signals) {
  PseudoTerminal pty;
  SimulatedSerialActuator actuator(pty.master_fd(), arguments.serial);
  actuator.Start();
  if (!arguments.link.empty()) {
    std::filesystem::remove(arguments.link);
    std::filesystem::create_symlink(pty.slave_path(), arguments.link);
  }
  std::cout << "serial actuator on " << pty.slave_path() << " (" << arguments.serial.axes
            << " axes)" << (arguments.link.empty() ? "" : ", link " + arguments.link) << std::endl;
  WaitForTermination(signals);
  actuator.Stop();
  if (!arguments.link.empty()) std::filesystem::remove(arguments.link);
  return 0;
}

int ServeCan(const SimArguments& arguments, const sigset_t& signals) {
  std::vector<std::unique_ptr<SimulatedCia402Drive>> drives;
  for (const int node : arguments.nodes) {
    SimulatedDriveOptions options;
    options.node_id = node;
    drives.push_back(
        std::make_unique<SimulatedCia402Drive>(OpenSocketCanBus(arguments.can_interface), options));
    drives.back()->PowerOn();
  }
  std::cout << "CiA 402 drives on " << arguments.can_interface << " (" << drives.size() << " nodes)"
            << std::endl;
  WaitForTermination(signals);
  return 0;
}

int Run(int argc, char** argv) {
  SimArguments arguments;
  CLI::App app{
      "A simulated tendon actuator: the serial line protocol on a new pseudo-terminal, "
      "or CiA 402 drives on a SocketCAN interface (see docs/actuators.md)."};
  app.add_option("--axes", arguments.serial.axes, "serial: axes")->check(CLI::Range(1, 32));
  app.add_option("--speed", arguments.serial.max_speed_mm_s, "serial: axis speed, mm/s")
      ->check(CLI::PositiveNumber);
  app.add_option("--travel", arguments.serial.travel_mm, "serial: travel of each axis, ± mm")
      ->check(CLI::PositiveNumber);
  app.add_option("--link", arguments.link, "serial: also make this symlink to the pty");
  app.add_option("--can", arguments.can_interface, "serve CiA 402 drives on this CAN interface");
  app.add_option("--nodes", arguments.nodes, "CAN: node ids of the drives")
      ->delimiter(',')
      ->check(CLI::Range(1, 127));
  if (const std::optional<int> exit_code = ParseCommandLine(app, argc, argv)) return *exit_code;
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);  // before any thread starts
  try {
    return arguments.can_interface.empty() ? ServeSerial(arguments, signals)
                                           : ServeCan(arguments, signals);
  } catch (const InputError& e) {
    std::cerr << "shapesense-actuator-sim: error: " << e.what() << std::endl;
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "shapesense-actuator-sim: failed: " << e.what() << std::endl;
    return kExitFailed;
  }
}

}  // namespace
}  // namespace shapesense

int main(int argc, char** argv) { return shapesense::Run(argc, argv); }
