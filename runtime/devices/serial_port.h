#pragma once

// A serial port for a line protocol: raw 8N1, no flow control, opened
// exclusively, read line by line with deadlines; and a pseudo-terminal pair,
// which is what the simulated actuator serves on.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "libs/actuation/line_protocol.h"
#include "runtime/devices/device_error.h"

namespace shapesense {

// The port hung up (a USB adapter unplugged, the pty's other end closed) or
// failed an I/O call. The message names the port and the cause.
class SerialLinkLost : public ActuatorError {
 public:
  using ActuatorError::ActuatorError;
};

class SerialPort {
 public:
  // Opens `path` (a tty or a symlink to one) non-blocking and without becoming
  // its controlling terminal, takes it exclusively (TIOCEXCL) and sets raw 8N1
  // at `baud` with no flow control. Throws ActuatorError naming the path.
  SerialPort(const std::string& path, int baud);
  ~SerialPort();
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  const std::string& path() const { return path_; }

  // Writes every byte before `deadline_us` (steady µs); SerialLinkLost on a
  // hang-up, an error, or a port that takes nothing until then.
  void Write(std::string_view bytes, int64_t deadline_us);
  // The next complete line (without '\n'), waiting until `deadline_us`;
  // nullopt on timeout. SerialLinkLost on a hang-up or an error.
  std::optional<std::string> ReadLine(int64_t deadline_us);
  // Drops what was received and not yet read; returns the complete lines dropped.
  int DiscardInput();

 private:
  // Reads what is there (waiting up to `timeout_ms`) into lines_.
  void ReadAvailable(int timeout_ms);
  [[noreturn]] void Lost(const std::string& what) const;

  std::string path_;
  int fd_ = -1;
  serial_protocol::LineAssembler assembler_;
  std::vector<std::string> lines_;
  size_t next_line_ = 0;
};

// A pseudo-terminal in raw mode. The slave side is the "serial port" a driver
// opens by path; the master side is the actuator's end. It keeps a descriptor
// of the slave open itself so the master never sees a hang-up while a driver
// reconnects.
class PseudoTerminal {
 public:
  // Throws ActuatorError when no pty can be made.
  PseudoTerminal();
  ~PseudoTerminal();
  PseudoTerminal(const PseudoTerminal&) = delete;
  PseudoTerminal& operator=(const PseudoTerminal&) = delete;

  int master_fd() const { return master_; }
  // /dev/pts/N.
  const std::string& slave_path() const { return slave_path_; }
  // Cuts the link: the driver's end hangs up.
  void Close();

 private:
  int master_ = -1;
  int slave_ = -1;
  std::string slave_path_;
};

}  // namespace shapesense
