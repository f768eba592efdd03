// The monitor's web server on loopback: its static files, its WebSocket's
// latest-message-per-channel delivery, and bad input (path traversal,
// oversized requests, malformed frames, a flood of connections) refused or
// bounded while it keeps serving.
#include "services/monitor/web_server.h"

// Boost 1.74's Asio uses std::exchange under C++20 without including
// <utility>, so <utility> comes first (clang-format would sort it after).
// clang-format off
#include <utility>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
// clang-format on
#include <gtest/gtest.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

namespace shapesense {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace fs = std::filesystem;
using tcp = asio::ip::tcp;

void WriteFile(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

// A page folder, and a secret beside it that no request may reach.
class Site {
 public:
  Site() : root_(fs::temp_directory_path() / ("web_server_test_" + std::to_string(getpid()))) {
    fs::remove_all(root_);
    WriteFile(root_ / "page" / "index.html", "<html>the page</html>");
    WriteFile(root_ / "page" / "app.js", "let x = 1;");
    WriteFile(root_ / "page" / "vendor" / "lib.js", "lib");
    WriteFile(root_ / "secret.txt", "SECRET");
    fs::create_symlink(root_ / "secret.txt", root_ / "page" / "link.txt");
  }
  ~Site() { fs::remove_all(root_); }
  fs::path page() const { return root_ / "page"; }

 private:
  fs::path root_;
};

tcp::endpoint EndpointOf(const WebServer& server) {
  const std::string address = server.address();
  const size_t colon = address.rfind(':');
  return {asio::ip::make_address(address.substr(0, colon)),
          static_cast<uint16_t>(std::stoi(address.substr(colon + 1)))};
}

// The raw answer to raw request bytes (the connection closed by the server
// or after 3 s). A server that refuses a request may close before it is all
// written: the rest is then not sent, and the answer may be lost to the reset.
std::string RawExchange(const WebServer& server, const std::string& request) {
  asio::io_context io;
  tcp::socket socket(io);
  socket.connect(EndpointOf(server));
  boost::system::error_code error;
  asio::write(socket, asio::buffer(request), error);
  socket.shutdown(tcp::socket::shutdown_send, error);
  std::string answer;
  char buffer[4096];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  while (std::chrono::steady_clock::now() < deadline) {
    const size_t n = socket.read_some(asio::buffer(buffer), error);
    answer.append(buffer, n);
    if (error) break;
  }
  return answer;
}

std::string Get(const WebServer& server, const std::string& target) {
  return RawExchange(server, "GET " + target + " HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
}

// A browser's WebSocket, read on demand.
class Client {
 public:
  explicit Client(const WebServer& server) : ws_(io_) {
    ws_.next_layer().connect(EndpointOf(server));
    ws_.handshake("127.0.0.1", "/ws");
  }
  std::string Read(bool* binary = nullptr) {
    beast::flat_buffer buffer;
    ws_.read(buffer);
    if (binary != nullptr) *binary = ws_.got_binary();
    return beast::buffers_to_string(buffer.data());
  }
  void Send(const std::string& text) { ws_.write(asio::buffer(text)); }

 private:
  asio::io_context io_;
  websocket::stream<tcp::socket> ws_;
};

WebServerOptions Options(const Site& site) {
  WebServerOptions options;
  options.listen = "127.0.0.1:0";
  options.folders["/"] = site.page();
  options.max_connections = 16;
  return options;
}

WebMessage Text(const std::string& text) {
  return {std::make_shared<const std::string>(text), false};
}

bool WaitUntil(const std::function<bool()>& done) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

TEST(StaticFileForTest, NamesOnlyFilesInsideTheFolders) {
  const Site site;
  const std::map<std::string, fs::path> folders = {{"/", site.page()}};
  EXPECT_EQ(StaticFileFor(folders, "/"), fs::canonical(site.page() / "index.html"));
  EXPECT_EQ(StaticFileFor(folders, "/app.js?v=2#x"), fs::canonical(site.page() / "app.js"));
  EXPECT_EQ(StaticFileFor(folders, "/vendor/lib.js"), fs::canonical(site.page() / "vendor/lib.js"));
  for (const char* bad : {"/../secret.txt", "/vendor/../../secret.txt", "/%2e%2e/secret.txt",
                          "/..%2fsecret.txt", "//secret.txt", "/./app.js", "/vendor/", "/link.txt",
                          "/missing.js", "/vendor\\..\\app.js", "relative.js"}) {
    EXPECT_TRUE(StaticFileFor(folders, bad).empty()) << bad;
  }
}

TEST(ContentTypeOfTest, KnowsThePagesTypes) {
  EXPECT_EQ(ContentTypeOf("a/index.html"), "text/html; charset=utf-8");
  EXPECT_EQ(ContentTypeOf("three.min.js"), "text/javascript; charset=utf-8");
  EXPECT_EQ(ContentTypeOf("style.css"), "text/css; charset=utf-8");
  EXPECT_EQ(ContentTypeOf("blob.bin"), "application/octet-stream");
}

TEST(WebServerTest, ServesThePageAndRefusesTraversal) {
  const Site site;
  WebServer server(
      Options(site), [] { return "hello"; }, [](const std::string&) { return ""; });
  const std::string page = Get(server, "/");
  EXPECT_NE(page.find("200 OK"), std::string::npos) << page;
  EXPECT_NE(page.find("text/html"), std::string::npos);
  EXPECT_NE(page.find("<html>the page</html>"), std::string::npos);
  for (const char* bad :
       {"/../secret.txt", "/vendor/../../secret.txt", "/%2e%2e/secret.txt", "/link.txt"}) {
    const std::string answer = Get(server, bad);
    EXPECT_NE(answer.find("404"), std::string::npos) << bad << ": " << answer;
    EXPECT_EQ(answer.find("SECRET"), std::string::npos) << bad;
  }
  const std::string post = RawExchange(
      server, "POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\nConnection: close\r\n\r\nhi");
  EXPECT_NE(post.find("405"), std::string::npos) << post;
  EXPECT_GE(server.Counters().bad_requests, 5);
}

TEST(WebServerTest, OversizedAndMalformedRequestsAreRefusedAndServingGoesOn) {
  const Site site;
  WebServer server(
      Options(site), [] { return "hello"; }, [](const std::string&) { return ""; });
  const std::string huge_header =
      "GET / HTTP/1.1\r\nHost: x\r\nX-Big: " + std::string(size_t{64} * 1024, 'a') +
      "\r\nConnection: close\r\n\r\n";
  EXPECT_EQ(RawExchange(server, huge_header).find("200 OK"), std::string::npos);
  EXPECT_TRUE(WaitUntil([&] { return server.Counters().bad_requests == 1; }));
  const std::string huge_body = "POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 10000000\r\n\r\n" +
                                std::string(size_t{100} * 1024, 'b');
  EXPECT_EQ(RawExchange(server, huge_body).find("200 OK"), std::string::npos);
  EXPECT_TRUE(WaitUntil([&] { return server.Counters().bad_requests == 2; }));
  EXPECT_NE(RawExchange(server, "NOT HTTP AT ALL\r\n\r\n").find("400"), std::string::npos);
  EXPECT_NE(Get(server, "/app.js").find("let x = 1;"), std::string::npos);
}

TEST(WebServerTest, AClientGetsTheGreetingThenTheLatestOfEachChannel) {
  const Site site;
  WebServer server(
      Options(site), [] { return "hello"; }, [](const std::string&) { return ""; });
  server.Publish("health", Text("health 1"));
  server.Publish("shape", Text("shape 1"));
  server.Publish("shape", Text("shape 2"));
  Client client(server);
  EXPECT_EQ(client.Read(), "hello");
  std::set<std::string> first = {client.Read(), client.Read()};
  EXPECT_EQ(first, (std::set<std::string>{"health 1", "shape 2"}));
  server.Publish("camera/cam0", {std::make_shared<const std::string>("\x01\x02jpeg"), true});
  bool binary = false;
  EXPECT_EQ(client.Read(&binary), "\x01\x02jpeg");
  EXPECT_TRUE(binary);
}

TEST(WebServerTest, ASlowClientGetsOnlyTheLatestAndDelaysNoOther) {
  const Site site;
  WebServer server(
      Options(site), [] { return "hello"; }, [](const std::string&) { return ""; });
  Client slow(server);
  Client quick(server);
  ASSERT_EQ(slow.Read(), "hello");
  ASSERT_EQ(quick.Read(), "hello");
  const std::string big(size_t{256} * 1024, 'x');  // fills the slow client's socket buffers at once
  constexpr int kMessages = 400;
  for (int i = 0; i < kMessages; ++i) {
    server.Publish("shape", Text(std::to_string(i) + ":" + big));
    // The quick client keeps up: it reads every message it is sent.
    const std::string got = quick.Read();
    EXPECT_EQ(got.substr(0, got.find(':')), std::to_string(i));
  }
  // The slow one read nothing meanwhile: most were replaced before sending.
  EXPECT_GT(server.Counters().messages_skipped, kMessages / 2);
  std::string last;
  while (last.substr(0, last.find(':')) != std::to_string(kMessages - 1)) last = slow.Read();
  EXPECT_EQ(last.substr(0, last.find(':')), std::to_string(kMessages - 1));
}

TEST(WebServerTest, AClientMessageIsAnsweredToThatClientAlone) {
  const Site site;
  WebServer server(
      Options(site), [] { return "hello"; },
      [](const std::string& text) { return text == "ping" ? std::string("pong") : ""; });
  Client asking(server);
  ASSERT_EQ(asking.Read(), "hello");
  asking.Send("ping");
  EXPECT_EQ(asking.Read(), "pong");
  EXPECT_TRUE(WaitUntil([&] { return server.Counters().client_messages == 1; }));
}

TEST(WebServerTest, MalformedAndOversizedFramesEndOnlyTheirSession) {
  const Site site;
  WebServerOptions options = Options(site);
  options.max_client_message_bytes = 1024;
  WebServer server(
      options, [] { return "hello"; }, [](const std::string&) { return ""; });
  {
    Client big(server);
    ASSERT_EQ(big.Read(), "hello");
    big.Send(std::string(4096, 'z'));
    EXPECT_THROW(big.Read(), boost::system::system_error);
  }
  // An upgrade, then bytes that are no WebSocket frame (unmasked, reserved bits).
  const std::string garbage =
      "GET /ws HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
      "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n" +
      std::string("\xff\xff\xff\xff\xff\xff\xff\xff garbage", 16);
  EXPECT_NE(RawExchange(server, garbage).find("101"), std::string::npos);
  EXPECT_TRUE(WaitUntil([&] { return server.Counters().client_errors >= 2; }));
  Client fine(server);
  EXPECT_EQ(fine.Read(), "hello");
  EXPECT_NE(Get(server, "/").find("200 OK"), std::string::npos);
}

TEST(WebServerTest, AHundredConnectionsAtOnceAreBoundedAndServingGoesOn) {
  const Site site;
  WebServer server(
      Options(site), [] { return "hello"; }, [](const std::string&) { return ""; });
  asio::io_context io;
  std::vector<tcp::socket> sockets;
  for (int i = 0; i < 100; ++i) {
    sockets.emplace_back(io);
    sockets.back().connect(EndpointOf(server));
  }
  EXPECT_TRUE(WaitUntil([&] { return server.Counters().accepted == 100; }));
  EXPECT_EQ(server.Counters().refused, 100 - 16);
  EXPECT_EQ(server.Counters().connections, 16);
  sockets.clear();
  EXPECT_TRUE(WaitUntil([&] { return server.Counters().connections == 0; }));
  EXPECT_NE(Get(server, "/").find("200 OK"), std::string::npos);
}

// A Foxglove client: the subprotocol, the server's info and advertisement,
// then message data for what it subscribed to alone.
TEST(WebServerTest, AFoxgloveClientGetsWhatItSubscribedToFramedAsItsProtocolSays) {
  const Site site;
  WebServerOptions options = Options(site);
  options.foxglove = {{"fox/shape", "/shapesense/shape", "shapesense.Shape", "{}"},
                      {"fox/health", "/shapesense/health", "shapesense.Health", "{}"}};
  WebServer server(
      options, [] { return "hello"; }, [](const std::string&) { return ""; });
  asio::io_context io;
  websocket::stream<tcp::socket> fox(io);
  fox.next_layer().connect(EndpointOf(server));
  fox.set_option(websocket::stream_base::decorator([](websocket::request_type& request) {
    request.set(http::field::sec_websocket_protocol, kFoxgloveSubprotocol);
  }));
  websocket::response_type handshake;
  fox.handshake(handshake, "127.0.0.1", "/ws");
  EXPECT_EQ(handshake[http::field::sec_websocket_protocol], kFoxgloveSubprotocol);
  const auto read = [&fox] {
    beast::flat_buffer buffer;
    fox.read(buffer);
    return beast::buffers_to_string(buffer.data());
  };
  const nlohmann::json info = nlohmann::json::parse(read());
  EXPECT_EQ(info["op"], "serverInfo");
  const nlohmann::json advertise = nlohmann::json::parse(read());
  ASSERT_EQ(advertise["op"], "advertise");
  ASSERT_EQ(advertise["channels"].size(), 2u);
  EXPECT_EQ(advertise["channels"][1]["id"], 2);
  EXPECT_EQ(advertise["channels"][1]["topic"], "/shapesense/health");
  EXPECT_EQ(advertise["channels"][1]["encoding"], "json");

  Client page(server);
  ASSERT_EQ(page.Read(), "hello");
  server.Publish("fox/shape", {std::make_shared<const std::string>("{\"a\":1}"), false, 1'500'000});
  server.Publish("shape", Text("page shape"));
  EXPECT_EQ(page.Read(), "page shape");  // the page never gets a Foxglove channel
  fox.write(
      asio::buffer(std::string(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":1}]})")));
  const std::string data = read();
  EXPECT_TRUE(fox.got_binary());
  ASSERT_EQ(data.size(), 13u + 7u);
  EXPECT_EQ(data[0], 1);                        // message data
  EXPECT_EQ(static_cast<uint8_t>(data[1]), 7);  // the subscription id
  uint64_t nanoseconds = 0;
  for (int i = 0; i < 8; ++i)
    nanoseconds |= static_cast<uint64_t>(static_cast<uint8_t>(data[5 + i])) << (8 * i);
  EXPECT_EQ(nanoseconds, 1'500'000'000u);
  EXPECT_EQ(data.substr(13), "{\"a\":1}");
  EXPECT_EQ(server.Counters().foxglove_clients, 1);
  // Unsubscribed (and a malformed request ignored), it gets nothing more.
  fox.write(asio::buffer(std::string("not json")));
  fox.write(asio::buffer(std::string(R"({"op":"unsubscribe","subscriptionIds":[7]})")));
  fox.write(
      asio::buffer(std::string(R"({"op":"subscribe","subscriptions":[{"id":8,"channelId":2}]})")));
  // Each request is handled on the server's thread as it is read, before any later publish.
  ASSERT_TRUE(WaitUntil([&] { return server.Counters().client_messages == 4; }));
  server.Publish("fox/shape", {std::make_shared<const std::string>("{\"a\":2}"), false, 0});
  server.Publish("fox/health", {std::make_shared<const std::string>("{\"h\":1}"), false, 0});
  EXPECT_EQ(read().substr(13), "{\"h\":1}");
}

TEST(WebServerTest, AnAddressInUseOrMalformedIsNamed) {
  const Site site;
  WebServer first(
      Options(site), [] { return ""; }, [](const std::string&) { return ""; });
  WebServerOptions options = Options(site);
  options.listen = first.address();
  try {
    WebServer second(
        options, [] { return ""; }, [](const std::string&) { return ""; });
    FAIL() << "a second server on " << first.address();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(first.address()), std::string::npos) << e.what();
  }
  options.listen = "localhost";
  EXPECT_THROW(WebServer(
                   options, [] { return ""; }, [](const std::string&) { return ""; }),
               std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
