// The web monitor against the live pipeline (the virtual rig's GigE cameras,
// capture, carving, shape) in the test's private network namespace: a
// Foxglove protocol client checks the advertised topics and one message of
// each, then headless Chromium (Debian's) opens the page
// (tests/browser/monitor_page_check.mjs): the camera panes and the 3-D view
// drawn, at least 10 updates a second, every service in the health table,
// and the shape service, killed, shown missing within 3 s.
#include <gtest/gtest.h>

// Boost 1.74's Asio uses std::exchange under C++20 without including
// <utility>, so <utility> comes first (clang-format would sort it after).
// clang-format off
#include <utility>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
// clang-format on
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/lcm_bus.h"
#include "tests/e2e/live_pipeline.h"

namespace shapesense::e2e {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
namespace fs = std::filesystem;
using nlohmann::json;
using std::chrono::milliseconds;
using std::chrono::seconds;
using tcp = asio::ip::tcp;

// "http://127.0.0.1:PORT/" from the monitor's first line.
std::string ServedUrl(const std::string& output) {
  const size_t start = output.find("http://");
  return start == std::string::npos ? "" : output.substr(start, output.find(' ', start) - start);
}

tcp::endpoint EndpointOf(const std::string& url) {
  const std::string host_port = url.substr(7, url.size() - 8);  // between "http://" and "/"
  const size_t colon = host_port.rfind(':');
  return {asio::ip::make_address(host_port.substr(0, colon)),
          static_cast<uint16_t>(std::stoi(host_port.substr(colon + 1)))};
}

// What a Foxglove client saw: the advertised topics, one message of each.
struct FoxgloveSession {
  std::map<std::string, json> channels;  // topic → its advertisement
  std::map<std::string, json> first;     // topic → its first message
};

// The topics a sensing pipeline without a controller publishes on.
const std::vector<std::string> kLiveTopics = {"/shapesense/shape",       "/shapesense/truth",
                                              "/shapesense/health",      "/shapesense/stats",
                                              "/camera/cam0/compressed", "/camera/cam1/compressed",
                                              "/camera/cam2/compressed"};

bool HasAll(const std::map<std::string, json>& first) {
  return std::all_of(kLiveTopics.begin(), kLiveTopics.end(),
                     [&](const std::string& topic) { return first.count(topic) > 0; });
}

// Subscribes to every topic advertised; returns once each of kLiveTopics
// has had a message, or at the timeout.
FoxgloveSession ListenAsFoxglove(const std::string& url, seconds timeout) {
  asio::io_context io;
  websocket::stream<beast::tcp_stream> ws(io);
  ws.next_layer().connect(EndpointOf(url));
  ws.set_option(websocket::stream_base::decorator([](websocket::request_type& request) {
    request.set(beast::http::field::sec_websocket_protocol, "foxglove.websocket.v1");
  }));
  ws.handshake("127.0.0.1", "/ws");
  FoxgloveSession session;
  std::map<uint32_t, std::string> topic_of_subscription;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline && !HasAll(session.first)) {
    beast::flat_buffer buffer;
    ws.next_layer().expires_at(deadline);
    ws.read(buffer);
    const std::string data = beast::buffers_to_string(buffer.data());
    if (ws.got_text()) {
      const json message = json::parse(data);
      if (message["op"] != "advertise") continue;
      json subscriptions = json::array();
      for (const json& channel : message["channels"]) {
        session.channels[channel["topic"]] = channel;
        topic_of_subscription[channel["id"].get<uint32_t>() + 100] = channel["topic"];
        subscriptions.push_back(
            {{"id", channel["id"].get<uint32_t>() + 100}, {"channelId", channel["id"]}});
      }
      ws.text(true);
      ws.write(asio::buffer(json{{"op", "subscribe"}, {"subscriptions", subscriptions}}.dump()));
      continue;
    }
    if (data.size() < 13 || data[0] != 1) continue;
    uint32_t subscription = 0;
    for (int i = 0; i < 4; ++i)
      subscription |= static_cast<uint32_t>(static_cast<uint8_t>(data[1 + i])) << (8 * i);
    const std::string topic = topic_of_subscription[subscription];
    if (!session.first.count(topic)) session.first[topic] = json::parse(data.substr(13));
  }
  return session;
}

constexpr const char* kToken = "e2e-estop-token-0123456789";

// A page's e-stop request with `token`; the monitor's answer.
json PressEstop(const std::string& url, const std::string& token) {
  asio::io_context io;
  websocket::stream<tcp::socket> ws(io);
  ws.next_layer().connect(EndpointOf(url));
  ws.handshake("127.0.0.1", "/ws");
  beast::flat_buffer hello;
  ws.read(hello);
  ws.write(asio::buffer(json{{"type", "estop"}, {"token", token}}.dump()));
  for (;;) {  // the latest of each channel comes too
    beast::flat_buffer buffer;
    ws.read(buffer);
    if (!ws.got_text()) continue;
    json message = json::parse(beast::buffers_to_string(buffer.data()));
    if (message["type"] == "estop_result") return message;
  }
}

class MonitorTest : public ::testing::Test {
 protected:
  MonitorTest() : pipeline_("monitor") {}

  // The monitor on a free port of the namespace's loopback, with an e-stop
  // token; its URL.
  std::string StartMonitor() {
    const fs::path token = pipeline_.dir() / "estop.token";
    std::ofstream(token) << kToken << '\n';
    fs::permissions(token, fs::perms::owner_read | fs::perms::owner_write);
    ChildOptions options;
    options.capture_stderr = true;
    options.log_file = pipeline_.dir() / "monitor.log";
    monitor_ = std::make_unique<ChildProcess>(
        std::vector<std::string>{E2E_MONITOR, "--http", "127.0.0.1:0", "--lcm-url", kLcmUrl,
                                 "--calibration", (pipeline_.dir() / "rig" / "rig.yaml").string(),
                                 "--estop-token-file", token.string(), "--duration", "600"},
        options);
    if (!monitor_->WaitForLine("serving http://", milliseconds(20000))) return "";
    return ServedUrl(monitor_->output());
  }

  LivePipeline pipeline_;
  std::unique_ptr<ChildProcess> monitor_;
};

TEST_F(MonitorTest, FoxgloveAndABrowserSeeTheLivePipelineAndAKilledServiceGoesMissing) {
  ASSERT_EQ(pipeline_.StartServices(), "");
  const std::string url = StartMonitor();
  ASSERT_FALSE(url.empty()) << monitor_->Tail(20);
  pipeline_.StartCapture(120.0);
  ASSERT_TRUE(pipeline_.recorder().WaitFor([&] { return pipeline_.recorder().ShapeCount() > 30; },
                                           milliseconds(60000)));

  const FoxgloveSession fox = ListenAsFoxglove(url, seconds(30));
  for (const char* topic : {"/shapesense/controller", "/shapesense/target"}) {
    EXPECT_TRUE(fox.channels.count(topic)) << topic << " not advertised";
  }
  for (const std::string& topic : kLiveTopics) {
    ASSERT_TRUE(fox.channels.count(topic)) << topic << " not advertised";
    EXPECT_EQ(fox.channels.at(topic)["encoding"], "json");
    EXPECT_EQ(fox.channels.at(topic)["schemaEncoding"], "jsonschema");
    EXPECT_TRUE(json::parse(fox.channels.at(topic)["schema"].get<std::string>()).is_object());
    ASSERT_TRUE(fox.first.count(topic)) << "no message on " << topic;
  }
  EXPECT_EQ(fox.channels.at("/camera/cam0/compressed")["schemaName"], "foxglove.CompressedImage");
  const json& shape = fox.first.at("/shapesense/shape");
  EXPECT_TRUE(shape["valid"]) << shape.dump();
  EXPECT_GT(shape["centerline"].size(), 50u);
  const json& image = fox.first.at("/camera/cam1/compressed");
  EXPECT_EQ(image["format"], "jpeg");
  EXPECT_EQ(image["frame_id"], "cam1");
  EXPECT_TRUE(image["data"].get<std::string>().starts_with("/9j/"));  // FF D8 FF in base64
  std::set<std::string> programs;
  for (const json& row : fox.first.at("/shapesense/health")["rows"])
    programs.insert(row["program"]);
  EXPECT_EQ(programs, (std::set<std::string>{"capture", "carving", "monitor", "rig_sim", "shape"}));

  // The e-stop: refused with a wrong token, published with the right one.
  LcmBus listener(kLcmUrl);
  std::vector<estop_t> estops;
  listener.Subscribe<estop_t>(channels::kEstop, [&](estop_t&& estop, const std::string&, int64_t) {
    estops.push_back(estop);
  });
  const json refused = PressEstop(url, "e2e-estop-token-0123456780");
  EXPECT_FALSE(refused["ok"]) << refused.dump();
  const json pressed = PressEstop(url, kToken);
  EXPECT_TRUE(pressed["ok"]) << pressed.dump();
  const auto estop_deadline = std::chrono::steady_clock::now() + seconds(5);
  while (estops.empty() && std::chrono::steady_clock::now() < estop_deadline) listener.Handle(100);
  ASSERT_EQ(estops.size(), 1u) << "one e-stop, from the right token only";
  EXPECT_TRUE(estops[0].engaged);
  EXPECT_NE(estops[0].source.find("shapesense-monitor"), std::string::npos) << estops[0].source;

  const fs::path out = pipeline_.dir() / "browser";
  const std::string kill = "kill -9 " + std::to_string(pipeline_.shape_service().pid());
  ChildOptions options;
  options.capture_stderr = true;
  options.log_file = pipeline_.dir() / "browser.log";
  ChildProcess browser(
      {E2E_NODE, E2E_PAGE_CHECK, "--url", url, "--out", out.string(), "--expect",
       "capture,carving,shape,rig_sim,monitor", "--kill-program", "shape", "--kill-command", kill},
      options);
  const auto deadline = std::chrono::steady_clock::now() + seconds(180);
  std::optional<int> status;
  while (!(status = browser.ExitStatus()) && std::chrono::steady_clock::now() < deadline) {
    browser.ReadAvailable();
    std::this_thread::sleep_for(milliseconds(100));
  }
  browser.ReadAvailable();
  ASSERT_TRUE(status.has_value()) << "the page check did not end in 180 s:\n" << browser.Tail(40);
  ASSERT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0)
      << DescribeExitStatus(*status) << "\n"
      << browser.Tail(60);
  const json result = json::parse(ReadTextFile(out / "result.json"));
  std::cout << "page check: " << result.dump() << '\n';
  EXPECT_TRUE(fs::exists(out / "monitor.png"));
}

}  // namespace
}  // namespace shapesense::e2e
