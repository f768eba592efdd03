#pragma once

// A simulated CiA 402 servo drive on a CanBus (the in-memory bus in tests,
// vcan0 where the kernel has CAN): NMT (boot-up, pre-operational,
// operational, resets), an expedited SDO server over its object dictionary,
// the heartbeat producer (1017h), configurable RPDO1/TPDO1 with SYNC
// transmission, EMCY, the CiA 402 power state machine and profile-position
// mode with the set-point handshake. Its motion: AxisMotion at the profile
// velocity. It serves from its own thread; faults and power loss can be
// injected.
//
// Simplifications, documented in docs/actuators.md: PDO 1 only (RPDO1/TPDO1);
// a new set-point always acts at once (as with "change set immediately");
// quick stop holds at once and stays in quick stop active (option code 6).

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "libs/actuation/axis_motion.h"
#include "libs/actuation/can_bus.h"
#include "libs/actuation/canopen.h"
#include "libs/actuation/cia402.h"
#include "libs/actuation/object_dictionary.h"

namespace shapesense {

struct SimulatedDriveOptions {
  int node_id = 1;
  uint32_t device_type = 0x00020192;   // 1000h: CiA 402, servo drive
  double max_velocity_counts_s = 1e7;  // 6081h above this is refused (value too high)
  int32_t initial_position = 0;        // counts
};

class SimulatedCia402Drive {
 public:
  struct Counters {
    int64_t setpoints = 0;   // new set-points taken (controlword bit 4 rising edges)
    int64_t rpdos = 0;       // RPDO1 frames applied
    int64_t tpdos = 0;       // TPDO1 frames sent
    int64_t sdo_aborts = 0;  // SDO requests answered with an abort
    int64_t emergencies = 0;
  };

  SimulatedCia402Drive(std::unique_ptr<CanBus> bus, SimulatedDriveOptions options);
  ~SimulatedCia402Drive();
  SimulatedCia402Drive(const SimulatedCia402Drive&) = delete;
  SimulatedCia402Drive& operator=(const SimulatedCia402Drive&) = delete;

  // Powers on: boot-up message, pre-operational, serving from its own thread.
  void PowerOn();
  // Powers off: the thread ends and the drive falls silent (no heartbeat, no answers).
  void PowerOff();

  // A drive fault: fault reaction, then fault, holding; the EMCY goes out with `error_code`.
  void InjectFault(uint16_t error_code);

  cia402::State state() const;
  uint8_t nmt_state() const;
  int32_t position() const;  // counts
  int32_t setpoint() const;  // the target the motion runs to, counts
  uint32_t Object(uint16_t index, uint8_t subindex) const;
  Counters counters() const;

 private:
  void Serve();
  void ServeOnce();
  void BootLocked(bool reset_application);
  void HandleLocked(const CanFrame& frame);
  void HandleNmtLocked(const CanFrame& frame);
  void HandleSyncLocked();
  void HandleSdoLocked(const CanFrame& frame);
  uint32_t CheckPdoConfigWriteLocked(uint16_t index, uint8_t subindex, uint32_t value) const;
  void HandleRpdoLocked(const CanFrame& frame);
  void ApplyRpdoLocked(const CanFrame& frame);
  void SendTpdoLocked();
  void ProcessControlwordLocked();
  void EnterFaultLocked(uint16_t error_code);
  void AdvanceLocked(int64_t now_us);
  void UpdateStatuswordLocked();
  void HeartbeatLocked(int64_t now_us);
  void SendLocked(const CanFrame& frame);
  bool PdoValidLocked(uint16_t communication_index) const;

  const SimulatedDriveOptions options_;
  std::unique_ptr<CanBus> bus_;
  mutable std::mutex mutex_;
  ObjectDictionary od_;
  uint8_t nmt_ = static_cast<uint8_t>(canopen::NmtState::kBootUp);
  cia402::State state_ = cia402::State::kNotReadyToSwitchOn;
  uint16_t previous_controlword_ = 0;
  bool setpoint_acknowledged_ = false;
  AxisMotion motion_;
  std::optional<CanFrame> pending_rpdo_;
  std::optional<uint16_t> pending_fault_;
  int sync_count_ = 0;
  int64_t last_advance_us_ = 0;
  int64_t next_heartbeat_us_ = 0;
  Counters counters_;
  std::atomic<bool> running_{false};
  std::thread thread_;
};

}  // namespace shapesense
