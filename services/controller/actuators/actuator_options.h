#pragma once

// The tendon actuators' configuration (config/actuators.yaml): which driver,
// how many tendons, and each driver's own section. Validated once, before any
// port or bus is opened.

#include <string>
#include <vector>

namespace shapesense {

// The serial line protocol of docs/actuators.md.
struct SerialActuatorOptions {
  std::string device = "/dev/ttyUSB0";
  int baud = 115200;
  double reply_timeout_s = 0.05;
  int retries = 2;
  double connect_timeout_s = 2.0;
  double device_watchdog_s = 1.0;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("device", device,
          "serial port (a tty, or a symlink to one such as /dev/serial/by-id/...)");
    visit("baud", baud, "line rate: 9600, 19200, 38400, 57600, 115200, 230400, 460800 or 921600");
    visit("reply_timeout_s", reply_timeout_s, "longest wait for one reply, s (0.001-5)");
    visit("retries", retries,
          "times a request is sent again after a timeout or a corrupt reply (0-10)");
    visit("connect_timeout_s", connect_timeout_s,
          "Connect keeps trying to open the port and get an answer this long, s (0-60)");
    visit("device_watchdog_s", device_watchdog_s,
          "the actuator holds when no valid line came for this long, s (0: off; 0.01-60)");
  }
  std::string Validate() const;
};

// A CANopen master for CiA 402 drives in profile-position mode, one node per tendon.
struct CanOpenOptions {
  std::string interface = "can0";
  std::vector<int> node_ids = {1, 2, 3, 4};
  double counts_per_mm = 1000.0;
  double profile_velocity_mm_s = 20.0;
  double profile_acceleration_mm_s2 = 200.0;
  double quick_stop_deceleration_mm_s2 = 1000.0;
  double heartbeat_period_s = 0.1;
  double heartbeat_timeout_s = 0.35;
  double sdo_timeout_s = 0.1;
  double pdo_timeout_s = 0.05;
  int pdo_retries = 1;
  double boot_timeout_s = 2.0;
  double state_timeout_s = 1.0;
  bool configure_pdos = true;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("interface", interface, "SocketCAN interface, e.g. can0 or vcan0");
    visit("node_ids", node_ids, "CANopen node id of each tendon's drive, in axis order (1-127)");
    visit("counts_per_mm", counts_per_mm,
          "drive position counts per mm of tendon displacement (negative flips the direction)");
    visit("profile_velocity_mm_s", profile_velocity_mm_s, "profile velocity (6081h), mm/s");
    visit("profile_acceleration_mm_s2", profile_acceleration_mm_s2,
          "profile acceleration and deceleration (6083h, 6084h), mm/s²");
    visit("quick_stop_deceleration_mm_s2", quick_stop_deceleration_mm_s2,
          "quick stop deceleration (6085h), mm/s²");
    visit("heartbeat_period_s", heartbeat_period_s,
          "heartbeat producer time set in every drive (1017h), s (0.01-10)");
    visit("heartbeat_timeout_s", heartbeat_timeout_s,
          "a drive silent this long is a fault, s (more than heartbeat_period_s)");
    visit("sdo_timeout_s", sdo_timeout_s, "longest wait for one SDO answer, s (0.001-5)");
    visit("pdo_timeout_s", pdo_timeout_s, "longest wait for every TPDO after a SYNC, s (0.001-5)");
    visit("pdo_retries", pdo_retries, "SYNCs sent again when a TPDO is missing (0-10)");
    visit("boot_timeout_s", boot_timeout_s,
          "longest wait for a drive's boot-up message after the NMT reset, s (0.01-60)");
    visit("state_timeout_s", state_timeout_s,
          "longest wait for one CiA 402 state transition, s (0.01-60)");
    visit("configure_pdos", configure_pdos,
          "map RPDO1 (6040h, 607Ah) and TPDO1 (6041h, 6064h) by SDO; false: check the "
          "drive already has them");
  }
  std::string Validate() const;
};

// The virtual rig's tendons: commanded displacements reach the plant through a
// first-order lag.
struct SimulatedActuatorOptions {
  double time_constant_s = 0.05;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("time_constant_s", time_constant_s,
          "first-order lag of each tendon, s (0: a tendon is where it is commanded)");
  }
  std::string Validate() const;
};

// The virtual rig's plant over LCM (the controller service's rig driver,
// services/controller/rig_plant_driver.h): targets go out on
// SHAPESENSE_PLANT_COMMAND, the actuators' positions come back on
// SHAPESENSE_PLANT_STATE.
struct RigActuatorOptions {
  double state_timeout_s = 0.5;
  double connect_timeout_s = 5.0;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("state_timeout_s", state_timeout_s,
          "no plant state for this long is a lost link, s (0.01-60)");
    visit("connect_timeout_s", connect_timeout_s,
          "Connect waits this long for the plant's first state, s (0.01-60)");
  }
  std::string Validate() const;
};

struct ActuatorOptions {
  std::string driver = "simulated";
  int tendons = 4;
  SerialActuatorOptions serial;
  CanOpenOptions canopen;
  SimulatedActuatorOptions simulated;
  RigActuatorOptions rig;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("driver", driver, "serial | socketcan | simulated | rig");
    visit("tendons", tendons, "tendons (axes) the driver commands (1-32)");
    visit("serial", serial, "driver: serial (the line protocol of docs/actuators.md)");
    visit("canopen", canopen, "driver: socketcan (CANopen CiA 402 drives, profile position)");
    visit("simulated", simulated, "driver: simulated (the virtual rig's tendons)");
    visit("rig", rig, "driver: rig (the virtual rig's plant over LCM)");
  }
  // Checks every section; node_ids must name one drive per tendon when the
  // driver is socketcan.
  std::string Validate() const;
};

}  // namespace shapesense
