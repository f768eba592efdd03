// What the web monitor costs (issue 15): the live pipeline of `shapesense
// demo --pipeline` at 30 Hz, in a private network namespace, run three times:
//   without a monitor;
//   with the monitor and three WebSocket clients that read every message (as
//     browsers would receive them, without a browser's own CPU on the machine);
//   with the monitor and three pages open in headless Chromium
//     (tests/browser/open_pages.mjs), at nice 19: on 2 cores, three software-
//     rendered WebGL pages at normal priority would take the pipeline's CPU,
//     where a rig's browsers run on other machines.
// The first two alternate twice, to show how much the figures move run to run.
// Prints, per run, the pipeline's trigger → shape latency p50 / p99 (from the
// demo's report), frame-sets measured per second, and the monitor's own CPU
// over the run (its getrusage, printed as it stops) with what the clients
// received. Asserts nothing: the figures depend on the machine and its load.
#include <CLI/CLI.hpp>

// Boost 1.74's Asio uses std::exchange under C++20 without including
// <utility>, so <utility> comes first (clang-format would sort it after).
// clang-format off
#include <utility>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
// clang-format on
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <regex>
#include <thread>

#include "clients/tools/demo/live_demo.h"
#include "runtime/file_io.h"
#include "runtime/process/child_process.h"
#include "runtime/process/listening_socket.h"
#include "runtime/process/private_network.h"

namespace shapesense::bench {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace fs = std::filesystem;
using nlohmann::json;
using tcp = asio::ip::tcp;

struct BenchOptions {
  double seconds = 30.0;
  int clients = 3;
  fs::path out = "monitor-bench";
  fs::path node = "/usr/bin/node";
  fs::path pages_script;  // tests/browser/open_pages.mjs (with its node_modules)
};

enum class Watchers { kNone, kWebSocket, kChromium };

struct RunResult {
  double p50_ms = 0.0;
  double p99_ms = 0.0;
  double measured_per_s = 0.0;
  std::string monitor_cpu;  // "cpu 1.2 s in 30.0 s (4.0% of a core)"
  int64_t messages = 0;     // received by the WebSocket clients
  int64_t bytes = 0;
  std::string pages;  // what open_pages.mjs said
};

// A client reading every message until the monitor goes away.
void ReadAll(const tcp::endpoint& endpoint, std::atomic<int64_t>& messages,
             std::atomic<int64_t>& bytes) {
  asio::io_context io;
  beast::websocket::stream<tcp::socket> ws(io);
  for (int attempt = 0; attempt < 1200; ++attempt) {  // the monitor starts after the backgrounds
    try {
      ws.next_layer().connect(endpoint);
      ws.handshake("127.0.0.1", "/ws");
      break;
    } catch (const std::exception&) {
      ws.next_layer().close();
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  try {
    for (;;) {
      beast::flat_buffer buffer;
      ws.read(buffer);
      ++messages;
      bytes += static_cast<int64_t>(buffer.size());
    }
  } catch (const std::exception&) {
    // the monitor stopped
  }
}

std::string MonitorCpu(const fs::path& log) {
  std::ifstream in(log);
  const std::regex cpu("cpu [0-9.]+ s in [0-9.]+ s \\([0-9.]+% of a core\\)");
  std::string line;
  std::smatch match;
  while (std::getline(in, line)) {
    if (std::regex_search(line, match, cpu)) return match.str();
  }
  return "(no monitor)";
}

RunResult Run(const BenchOptions& options, const std::string& name, bool monitor,
              Watchers watchers) {
  LiveDemoArgs live;
  live.out = options.out / name;
  live.duration_s = options.seconds;
  live.replay = false;
  live.progress = DemoProgress::kOff;
  const int socket = monitor ? OpenListeningSocket("127.0.0.1:0") : -1;
  live.monitor_socket = socket;
  const std::string address = monitor ? ListeningAddress(socket) : "";
  std::atomic<int64_t> messages{0}, bytes{0};
  std::vector<std::thread> clients;
  std::unique_ptr<ChildProcess> pages;
  if (watchers == Watchers::kWebSocket) {
    const size_t colon = address.rfind(':');
    const tcp::endpoint endpoint(asio::ip::make_address(address.substr(0, colon)),
                                 static_cast<uint16_t>(std::stoi(address.substr(colon + 1))));
    for (int i = 0; i < options.clients; ++i) {
      clients.emplace_back([&, endpoint] { ReadAll(endpoint, messages, bytes); });
    }
  } else if (watchers == Watchers::kChromium) {
    ChildOptions child;
    child.capture_stderr = true;
    child.nice = 19;
    pages = std::make_unique<ChildProcess>(
        std::vector<std::string>{options.node.string(), options.pages_script.string(), "--url",
                                 "http://" + address + "/", "--pages",
                                 std::to_string(options.clients), "--seconds",
                                 std::to_string(options.seconds + 600)},
        child);
  }
  std::ofstream log(options.out / (name + ".log"));
  const std::atomic<bool> stop{false};
  RunLiveDemo(live, stop, log);
  for (std::thread& client : clients) client.join();
  RunResult result;
  if (pages) {
    pages->Stop();
    const std::string output = pages->output();
    const size_t last = output.rfind("open_pages: ");
    result.pages = last == std::string::npos ? output : output.substr(last);
  }
  if (socket >= 0) close(socket);
  const json report = json::parse(ReadTextFile(live.out / "report.json"));
  result.p50_ms = report["latency_ms"]["trigger_to_shape"]["p50"];
  result.p99_ms = report["latency_ms"]["trigger_to_shape"]["p99"];
  result.measured_per_s = report["frame_sets"]["measured_per_s"];
  result.monitor_cpu = MonitorCpu(live.out / "logs" / "monitor.log");
  result.messages = messages;
  result.bytes = bytes;
  return result;
}

void Print(const std::string& name, const RunResult& result) {
  std::printf("%-34s trigger->shape p50 %6.1f ms  p99 %6.1f ms  %5.1f sets/s  monitor %s\n",
              name.c_str(), result.p50_ms, result.p99_ms, result.measured_per_s,
              result.monitor_cpu.c_str());
  if (result.messages > 0) {
    std::printf("%-34s the clients received %lld messages, %.1f MB\n", "",
                static_cast<long long>(result.messages), static_cast<double>(result.bytes) / 1e6);
  }
  if (!result.pages.empty()) std::printf("%-34s %s\n", "", result.pages.c_str());
  std::fflush(stdout);
}

int RunBench(int argc, char** argv) {
  CLI::App app{"monitor_bench: what the web monitor costs the live pipeline"};
  BenchOptions options;
  app.add_option("--seconds", options.seconds, "measured seconds per run")->capture_default_str();
  app.add_option("--clients", options.clients, "WebSocket clients, then browser pages")
      ->capture_default_str();
  app.add_option("--out", options.out, "output folder")->capture_default_str();
  app.add_option("--node", options.node, "node")->capture_default_str();
  app.add_option("--pages-script", options.pages_script, "tests/browser/open_pages.mjs")
      ->required();
  CLI11_PARSE(app, argc, argv);
  fs::create_directories(options.out);
  std::printf("monitor_bench: the demo's live pipeline at 30 Hz for %.0f s per run\n",
              options.seconds);
  const std::string clients = std::to_string(options.clients);
  for (const char* round : {"1", "2"}) {
    Print(std::string("no monitor (") + round + ")",
          Run(options, std::string("no_monitor_") + round, false, Watchers::kNone));
    Print("monitor, " + clients + " WebSocket clients (" + round + ")",
          Run(options, std::string("websocket_clients_") + round, true, Watchers::kWebSocket));
  }
  Print("monitor, " + clients + " Chromium pages (nice 19)",
        Run(options, "chromium_pages", true, Watchers::kChromium));
  return 0;
}

}  // namespace
}  // namespace shapesense::bench

int main(int argc, char** argv) {
  // First, while this process has one thread.
  shapesense::EnterNetwork(shapesense::NetworkMode::kPrivate, 8);
  return shapesense::bench::RunBench(argc, argv);
}
