#pragma once

// The CANopen master for CiA 402 drives in profile-position mode, one drive
// (node) per tendon, over any CanBus (SocketCAN on a rig, the in-memory bus
// in tests). See docs/actuators.md for the sequence on the wire.
//
// Connect: NMT reset communication and boot-up of every node; by SDO: device
// type check, heartbeat producer time, PDO mapping (or a check of it), mode 1
// (profile position), profile velocity and ramps; NMT start; the CiA 402
// state machine to operation enabled holding the actual position.
// Cyclic (driven by the caller, no thread of its own): RPDO1 (controlword,
// target) with the new-set-point handshake, SYNC, TPDO1 (statusword, actual
// position). Every call first handles what arrived since the last one: an
// EMCY, a drive's statusword fault, a drive leaving operation enabled or
// operational, or a heartbeat older than its timeout is a fault; the master
// then quick-stops every drive and sends no target until Connect().

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "libs/actuation/can_bus.h"
#include "libs/actuation/canopen.h"
#include "libs/actuation/cia402.h"
#include "services/controller/actuators/actuator_driver.h"
#include "services/controller/actuators/actuator_options.h"
#include "services/controller/actuators/sdo_client.h"

namespace shapesense {

class CanOpenActuatorDriver : public ActuatorDriver {
 public:
  // Opens the bus at each Connect(); throws CanBusError when it cannot.
  using BusOpener = std::function<std::unique_ptr<CanBus>()>;

  // `bus_name` names the bus in messages ("socketcan can0").
  CanOpenActuatorDriver(CanOpenOptions options, BusOpener open_bus, std::string bus_name);
  ~CanOpenActuatorDriver() override;

  int axis_count() const override { return static_cast<int>(nodes_.size()); }
  std::string description() const override { return bus_name_; }
  void Connect() override;
  void Disconnect() override;
  void CommandTargets(std::span<const double> target_mm) override;
  ActuatorPositions ReadPositions() override;
  ActuatorStatus Status() override;
  void Stop() override;
  ActuatorHealth Health() override;

 private:
  struct Node {
    int id = 0;
    bool booted = false;
    uint8_t nmt_state = 0;
    int64_t last_heartbeat_us = 0;  // steady
    bool tpdo_fresh = false;        // a TPDO1 came since the last SYNC
    uint16_t statusword = 0;
    int32_t position = 0;  // counts
    int32_t target = 0;    // counts, the last commanded
    std::string last_emergency;
  };
  // A fault or a lost link found while receiving; the caller raises it.
  struct Trouble {
    ActuatorState state = ActuatorState::kFault;
    uint32_t code = 0;
    std::string reason;
  };

  // Bring-up.
  void BringUp();
  void ResetAndAwaitBootUp();
  void ConfigureNode(const Node& node);
  void MapPdo(int id, uint16_t communication, uint16_t mapping, uint32_t cob_id,
              std::span<const canopen::PdoEntry> entries);
  void CheckPdo(int id, uint16_t communication, uint16_t mapping, uint32_t cob_id,
                std::span<const canopen::PdoEntry> entries);
  void EnableOperation(Node& node);
  cia402::State ReadState(int id);
  cia402::State AwaitStateChange(int id, cia402::State from, const std::string& after);
  void WriteControlword(int id, uint16_t controlword);

  // Receiving.
  void Dispatch(const CanFrame& frame);
  void OnHeartbeat(Node& node, uint8_t state);
  void OnTpdo(Node& node, const CanFrame& frame);
  void DrainBus();
  void CheckHeartbeats();
  // Handles what arrived; throws the trouble it found.
  void Supervise();

  // The PDO cycle.
  void SendRpdo(const Node& node, uint16_t controlword);
  // One SYNC: true when every node's TPDO1 came within the PDO timeout.
  bool SyncRound();
  // SYNCs until every node's TPDO1 satisfies `done`; the epoch time of that SYNC.
  int64_t SyncUntil(const std::function<bool(const Node&)>& done, const char* what);
  Trouble MissingTpdoTrouble() const;

  // Faults.
  // Turns a trouble, an SDO error or a bus error met inside `talk` into the
  // state (Raise) and throws ActuatorError.
  template <class Talk>
  auto Guarded(Talk&& talk);
  // The state becomes `state`; every drive is quick-stopped.
  void Raise(ActuatorState state, uint32_t code, const std::string& reason);
  void QuickStopAll();
  void RequireState(bool allow_fault, const char* action) const;
  Node* FindNode(int id);
  std::string NodeName(int id) const;

  const CanOpenOptions options_;
  const BusOpener open_bus_;
  const std::string bus_name_;
  std::vector<Node> nodes_;
  std::unique_ptr<CanBus> bus_;
  std::unique_ptr<SdoClient> sdo_;
  std::optional<Trouble> trouble_;
  // Connected: heartbeats, EMCYs and statuswords are faults when they say so.
  bool supervising_ = false;
  ActuatorStatus status_{ActuatorState::kDisconnected, "not connected yet", 0};
  ActuatorHealth health_;
};

}  // namespace shapesense
