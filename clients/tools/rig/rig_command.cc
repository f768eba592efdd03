#include "clients/tools/rig/rig_command.h"

#include <unistd.h>

#include <chrono>
#include <iostream>
#include <optional>
#include <stdexcept>

#include "libs/core/error.h"
#include "runtime/command_line.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/process/signal_thread.h"
#include "runtime/rig/rig_check.h"
#include "runtime/rig/rig_status.h"
#include "runtime/rig/rig_units.h"

namespace shapesense {
namespace {

RigFile ReadRig(const std::filesystem::path& file) {
  return ParseRigFile(ReadTextFile(file), file);
}

// The folder of the running `shapesense`: the services are installed beside it.
std::filesystem::path OwnFolder() {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::filesystem::path("/usr/local/bin") : self.parent_path();
}

LcmBusOptions StatusBusOptions(const RigStatusArgs& args, const std::optional<RigFile>& rig) {
  LcmBusOptions options = LcmBusOptions::FromEnvironment(args.lcm_url);
  if (rig && args.lcm_url.empty()) {
    options.url = rig->rig_network;
    options.local_url = rig->local_network;
    options.prefix = rig->prefix;
    options.routes = rig->channels;
  }
  // It reads the status and acts on nothing: no key needed on a workstation.
  options.auth.read_only = true;
  return options;
}

// Handles the bus until `until` (µs, this host's clock) or a stop.
void Listen(LcmBus& bus, int64_t until, const std::atomic<bool>& stop) {
  while (!stop.load() && NowUtime() < until) bus.Handle(50);
}

}  // namespace

int RunRigStatus(const RigStatusArgs& args, const std::atomic<bool>& stop, std::ostream& out) {
  std::optional<RigFile> rig;
  if (!args.rig.empty()) rig = ReadRig(args.rig);
  RigStatusBoard board(rig);
  LcmBus bus(StatusBusOptions(args, rig));
  bus.Subscribe<service_status_t>(
      channels::kStatusPattern,
      [&](service_status_t&& status, const std::string&, int64_t receive_utime) {
        board.Observe(status, receive_utime);
      });
  bus.Subscribe<shape_t>(channels::kShape, [&](shape_t&& shape, const std::string&, int64_t) {
    board.Observe(shape);
  });
  const int64_t start = NowUtime();
  // Two status periods: every running program has spoken at least once.
  constexpr int64_t kFirstLook = 2'500'000;
  Listen(bus, start + kFirstLook, stop);
  const bool live = !args.once;
  const bool terminal = isatty(STDOUT_FILENO) != 0 && &out == &std::cout;
  while (true) {
    const int64_t now = NowUtime();
    if (terminal && live) out << "\x1b[H\x1b[2J";  // redraw in place
    out << (args.json ? board.Json(now) + "\n" : board.Table(now)) << std::flush;
    const bool over =
        args.duration_s > 0 && now - start >= static_cast<int64_t>(args.duration_s * 1e6);
    if (!live || stop.load() || over) return board.Complete(now) ? 0 : 1;
    Listen(bus, now + 1'000'000, stop);
  }
}

int RunRigCheck(const std::vector<std::filesystem::path>& files, std::ostream& out) {
  std::vector<RigFile> rigs;
  std::vector<std::string> problems;
  for (const std::filesystem::path& file : files) {
    rigs.push_back(ReadRig(file));
    const std::vector<std::string> found = CheckRig(rigs.back());
    problems.insert(problems.end(), found.begin(), found.end());
  }
  const std::vector<std::string> shared = CheckRigsApart(rigs);
  problems.insert(problems.end(), shared.begin(), shared.end());
  for (const std::string& problem : problems) out << "  " << problem << '\n';
  if (problems.empty()) {
    for (const RigFile& rig : rigs) {
      size_t programs = 0;
      for (const RigHost& host : rig.hosts) programs += host.programs.size();
      out << rig.path.string() << ": rig " << rig.name << ", " << rig.hosts.size() << " hosts, "
          << programs << " programs, " << rig.cameras.size() << " cameras: ok\n";
    }
  }
  return static_cast<int>(problems.size());
}

int RunRigUnits(const std::filesystem::path& file, const std::string& host,
                const std::filesystem::path& out_dir, const std::filesystem::path& bin_dir,
                std::ostream& out) {
  const RigFile rig = ReadRig(file);
  std::vector<UnitFile> units;
  try {
    units = UnitsForHost(rig, host, bin_dir.empty() ? OwnFolder() : bin_dir);
  } catch (const std::invalid_argument& error) {
    throw InputError(error.what());
  }
  std::filesystem::create_directories(out_dir);
  for (const UnitFile& unit : units) {
    WriteFileAtomically(out_dir / unit.file_name, unit.text);
    out << (out_dir / unit.file_name).string() << '\n';
  }
  return static_cast<int>(units.size());
}

void AddRigCommand(CLI::App& app) {
  CLI::App* rig_app =
      app.add_subcommand("rig", "a rig of several hosts: check its file, make units");
  rig_app->require_subcommand(1);

  static std::vector<std::filesystem::path> check_files;
  CLI::App* check = rig_app->add_subcommand(
      "check", "validate rig files: hosts, programs, channels, networks (docs/rig.md)");
  check->add_option("files", check_files, "rig files (several: also that no two share a group)")
      ->required()
      ->check(CLI::ExistingFile);
  check->callback([] {
    const int problems = RunRigCheck(check_files, std::cout);
    if (problems > 0) {
      throw InputError(std::to_string(problems) + " problem(s) in the rig file(s), listed above");
    }
  });

  static std::filesystem::path units_file, units_out, units_bin;
  static std::string units_host;
  CLI::App* units =
      rig_app->add_subcommand("units", "write a host's systemd units (then deploy/rig/install.sh)");
  units->add_option("file", units_file, "rig file")->required()->check(CLI::ExistingFile);
  units->add_option("--host", units_host, "the host, as named in the rig file")->required();
  units->add_option("--out", units_out, "folder to write the units into")->required();
  units->add_option("--bin-dir", units_bin,
                    "where the programs are installed (default: beside this shapesense)");
  units->callback([] {
    const std::vector<std::string> problems = CheckRig(ReadRig(units_file));
    for (const std::string& problem : problems) std::cerr << "  " << problem << '\n';
    if (!problems.empty()) throw InputError("the rig file has problems (listed above): no units");
    RunRigUnits(units_file, units_host, units_out, units_bin, std::cout);
  });

  static RigStatusArgs status_args;
  CLI::App* status = rig_app->add_subcommand(
      "status", "every program of every host: up, stale or missing, with its health");
  status->add_option("--rig", status_args.rig, "rig file: the programs expected")
      ->check(CLI::ExistingFile);
  status->add_option("--lcm-url", status_args.lcm_url,
                     "the rig network (default: the rig file's, else LCM_DEFAULT_URL)");
  status->add_flag("--once", status_args.once, "listen 2.5 s, print once, exit");
  status->add_flag("--json", status_args.json, "JSON instead of a table");
  status->add_option("--duration", status_args.duration_s, "live: stop after this, s (0: Ctrl-C)");
  status->callback([] {
    const int code = RunRigStatus(status_args, StopFlagOnSignals(), std::cout);
    if (code != 0) throw std::runtime_error("an expected program is missing or stale (above)");
  });
}

}  // namespace shapesense
