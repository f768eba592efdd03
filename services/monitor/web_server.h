#pragma once

// The monitor's web side: static files over HTTP and a WebSocket (/ws) that
// carries the latest message of each channel to every browser. Boost.Beast
// over Asio, one I/O thread (docs/monitor.md says why Beast).
//
// Backpressure: each client holds at most one message per channel, the
// latest. A new one replaces an unsent one (counted as skipped), so a slow
// browser sees fewer updates and never delays the publisher or the other
// clients: Publish only swaps a pointer and wakes the I/O thread.
//
// Bad input is bounded: request headers and bodies by size, a browser's
// WebSocket messages by size, each connection by an idle timeout, the
// number of connections by max_connections (the next is closed at once),
// static paths to the asset folders (no "..", no escape through links).
// Knows nothing of LCM: the monitor service feeds it (monitor_service.h).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace shapesense {

// A channel also offered to Foxglove and Lichtblick over their WebSocket
// protocol (ws-protocol v1, subprotocol "foxglove.websocket.v1", on the same
// port): advertised as a JSON-encoded topic with its JSON Schema, sent to a
// client once it subscribes.
struct FoxgloveChannel {
  std::string channel;      // the channel whose messages it carries ("fox/shape")
  std::string topic;        // "/shapesense/shape"
  std::string schema_name;  // "shapesense.Shape", "foxglove.CompressedImage"
  std::string schema;       // JSON Schema (text)
};

// The Foxglove WebSocket subprotocol the server speaks.
inline constexpr const char* kFoxgloveSubprotocol = "foxglove.websocket.v1";

struct WebServerOptions {
  // "HOST:PORT" to listen on; port 0 picks a free one (address() tells).
  std::string listen = "127.0.0.1:8080";
  // An open listening TCP socket to serve instead (systemd's socket
  // activation, or the demo's socket made in the host's network); -1: none.
  int listen_fd = -1;
  // URL prefix ("/", "/vendor/") → folder served under it.
  std::map<std::string, std::filesystem::path> folders;
  int max_connections = 64;               // HTTP and WebSocket together
  int64_t max_request_bytes = 16 * 1024;  // header + body of an HTTP request
  int64_t max_client_message_bytes = 4096;
  double idle_timeout_s = 30.0;  // an HTTP connection that sends nothing
  // Channels for Foxglove clients (channel ids 1, 2, ... in this order); a
  // page client never gets them, a Foxglove client gets nothing else.
  std::vector<FoxgloveChannel> foxglove;
  std::string name = "shapesense-monitor";  // the server's name to Foxglove
};

struct WebServerCounters {
  int64_t clients = 0;           // WebSocket clients now
  int64_t connections = 0;       // open TCP connections now (HTTP + WebSocket)
  int64_t accepted = 0;          // TCP connections accepted in all
  int64_t refused = 0;           // closed at once: max_connections reached
  int64_t http_requests = 0;     // answered
  int64_t bad_requests = 0;      // malformed, oversized, or outside the folders
  int64_t messages_sent = 0;     // WebSocket messages written
  int64_t bytes_sent = 0;        // their payload bytes
  int64_t messages_skipped = 0;  // replaced by a newer one before it was sent
  int64_t client_messages = 0;   // received from browsers
  int64_t client_errors = 0;     // WebSocket sessions ended by a protocol error
  int64_t foxglove_clients = 0;  // of `clients`, those speaking Foxglove's protocol
};

// The payload of one channel's latest message.
struct WebMessage {
  std::shared_ptr<const std::string> payload;
  bool binary = false;
  int64_t utime = 0;  // what it shows, µs since the epoch (Foxglove's timestamp)
};

class WebServer {
 public:
  // Called for each new WebSocket client: its first message (the `hello`).
  using Greeting = std::function<std::string()>;
  // Called (on the I/O thread) with each text message a browser sends; what
  // it returns (if not empty) is sent back to that browser alone.
  using ClientMessage = std::function<std::string(const std::string& text)>;

  // Listens (throws std::runtime_error naming the address when it cannot)
  // and serves on a thread of its own until destroyed.
  WebServer(const WebServerOptions& options, Greeting greeting, ClientMessage on_message);
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  // "127.0.0.1:8080", as bound.
  std::string address() const;
  // From any thread: `channel`'s latest message, for every client now and
  // every client that connects later.
  void Publish(const std::string& channel, WebMessage message);
  WebServerCounters Counters() const;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// The file under one of `folders` that an HTTP target names, or empty when
// it names none: the query and fragment dropped, "/" → "/index.html";
// refused when percent-encoded, or holding "..", a backslash, a NUL or an
// empty segment, and when the resolved file lies outside its folder.
std::filesystem::path StaticFileFor(const std::map<std::string, std::filesystem::path>& folders,
                                    const std::string& target);
// "text/html; charset=utf-8" for ".html", … by extension.
std::string ContentTypeOf(const std::filesystem::path& file);

}  // namespace shapesense
