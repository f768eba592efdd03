#pragma once

// What the kernel knows about the bench and the services it started (its
// child processes), read from /proc: CPU time, and the datagrams each one's
// LCM receive socket lost because its buffer was full. Read before and after
// a step, the difference tells which process ran out of CPU or buffer.
#include <cstdint>
#include <map>
#include <string>

namespace shapesense::bench {

struct ProcessProbe {
  std::string name;          // the program's file name
  double cpu_seconds = 0.0;  // user + system, all threads
  int64_t udp_drops = 0;     // datagrams dropped at its sockets bound to the port
  int64_t udp_queued = 0;    // bytes waiting in those sockets now
};

// This process and its children, by pid. Processes that end or cannot be
// read are left out; never throws.
std::map<int, ProcessProbe> ProbeProcesses(int udp_port);

}  // namespace shapesense::bench
