#include "tests/bench/process_probe.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

namespace shapesense::bench {
namespace {

namespace fs = std::filesystem;

struct UdpSocket {
  int64_t drops = 0;
  int64_t queued = 0;
};

// Sockets of this network namespace bound to `port`, by inode
// (/proc/net/udp: sl local rem st tx:rx tr:when retrnsmt uid timeout inode ref pointer drops).
std::map<std::string, UdpSocket> UdpSocketsOnPort(int port) {
  std::map<std::string, UdpSocket> sockets;
  std::ifstream file("/proc/self/net/udp");
  std::string line;
  std::getline(file, line);  // the column names
  while (std::getline(file, line)) {
    std::istringstream fields(line);
    std::vector<std::string> f;
    for (std::string field; fields >> field;) f.push_back(field);
    if (f.size() < 13) continue;
    const size_t colon = f[1].find(':');
    if (colon == std::string::npos || std::stoi(f[1].substr(colon + 1), nullptr, 16) != port)
      continue;
    const size_t queue_colon = f[4].find(':');
    sockets["socket:[" + f[9] + "]"] = {std::stoll(f[12]),
                                        std::stoll(f[4].substr(queue_colon + 1), nullptr, 16)};
  }
  return sockets;
}

// From /proc/<pid>/stat: parent pid and user + system CPU time, s.
bool ReadStat(int pid, int* parent, double* cpu_seconds) {
  std::ifstream file("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  if (!std::getline(file, text)) return false;
  const size_t close = text.rfind(')');  // the name may hold spaces and parentheses
  if (close == std::string::npos) return false;
  std::istringstream rest(text.substr(close + 2));
  std::vector<std::string> f;
  for (std::string field; f.size() < 13 && rest >> field;) f.push_back(field);
  if (f.size() < 13) return false;
  *parent = std::stoi(f[1]);  // fields from the state on: state ppid ... utime(11) stime(12)
  *cpu_seconds = static_cast<double>(std::stoll(f[11]) + std::stoll(f[12])) /
                 static_cast<double>(sysconf(_SC_CLK_TCK));
  return true;
}

std::string ProgramName(int pid) {
  std::error_code error;
  const fs::path exe = fs::read_symlink("/proc/" + std::to_string(pid) + "/exe", error);
  return error ? "pid " + std::to_string(pid) : exe.filename().string();
}

void AddSocketCounters(int pid, const std::map<std::string, UdpSocket>& sockets,
                       ProcessProbe* probe) {
  std::error_code error;
  for (const auto& fd : fs::directory_iterator("/proc/" + std::to_string(pid) + "/fd", error)) {
    std::error_code link_error;
    const auto socket = sockets.find(fs::read_symlink(fd.path(), link_error).string());
    if (link_error || socket == sockets.end()) continue;
    probe->udp_drops += socket->second.drops;
    probe->udp_queued += socket->second.queued;
  }
}

}  // namespace

std::map<int, ProcessProbe> ProbeProcesses(int udp_port) {
  std::map<int, ProcessProbe> probes;
  try {
    const std::map<std::string, UdpSocket> sockets = UdpSocketsOnPort(udp_port);
    const int self = static_cast<int>(getpid());
    std::error_code error;
    for (const auto& entry : fs::directory_iterator("/proc", error)) {
      const std::string name = entry.path().filename().string();
      if (name.find_first_not_of("0123456789") != std::string::npos) continue;
      const int pid = std::stoi(name);
      int parent = 0;
      ProcessProbe probe;
      if (!ReadStat(pid, &parent, &probe.cpu_seconds) || (pid != self && parent != self)) continue;
      probe.name = ProgramName(pid);
      AddSocketCounters(pid, sockets, &probe);
      probes[pid] = probe;
    }
  } catch (const std::exception&) {
    // A process that ended mid-read, or a /proc this bench does not understand:
    // the probe is a diagnosis, not a measurement the run depends on.
  }
  return probes;
}

}  // namespace shapesense::bench
