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

#include <array>
#include <atomic>
#include <chrono>
#include <deque>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <nlohmann/json.hpp>

namespace shapesense {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

namespace {

constexpr size_t kMaxDirectMessages = 16;  // greetings and replies waiting for one client

std::chrono::milliseconds Millis(double seconds) {
  return std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000.0));
}

bool SafeRelativePath(const std::string& path) {
  if (path.find_first_of("\\%") != std::string::npos) return false;
  if (path.find('\0') != std::string::npos) return false;
  std::istringstream segments(path);
  std::string segment;
  while (std::getline(segments, segment, '/')) {
    if (segment.empty() || segment == "." || segment == "..") return false;
  }
  return !path.empty() && path.back() != '/';
}

// The file, or empty when it lies outside `folder` once links are resolved.
std::filesystem::path InsideFolder(const std::filesystem::path& folder,
                                   const std::string& relative) {
  std::error_code error;
  const std::filesystem::path root = std::filesystem::canonical(folder, error);
  if (error) return {};
  const std::filesystem::path file = std::filesystem::canonical(root / relative, error);
  if (error || !std::filesystem::is_regular_file(file, error)) return {};
  const auto [root_end, unused] = std::mismatch(root.begin(), root.end(), file.begin(), file.end());
  return root_end == root.end() ? file : std::filesystem::path{};
}

std::string ReadWholeFile(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

tcp::endpoint ParseEndpoint(const std::string& listen) {
  const size_t colon = listen.rfind(':');
  if (colon == std::string::npos) {
    throw std::invalid_argument("--http '" + listen + "': expected HOST:PORT");
  }
  std::string host = listen.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  }
  boost::system::error_code error;
  const asio::ip::address address = asio::ip::make_address(host, error);
  const std::string port = listen.substr(colon + 1);
  if (error || port.empty() || port.find_first_not_of("0123456789") != std::string::npos ||
      std::stoul(port) > 65535) {
    throw std::invalid_argument("--http '" + listen + "': expected an IP address and a port");
  }
  return {address, static_cast<uint16_t>(std::stoul(port))};
}

}  // namespace

std::filesystem::path StaticFileFor(const std::map<std::string, std::filesystem::path>& folders,
                                    const std::string& target) {
  std::string path = target.substr(0, target.find_first_of("?#"));
  if (path == "/") path = "/index.html";
  const std::pair<const std::string, std::filesystem::path>* best = nullptr;
  for (const auto& folder : folders) {
    if (path.rfind(folder.first, 0) == 0 && (!best || folder.first.size() > best->first.size())) {
      best = &folder;
    }
  }
  if (best == nullptr) return {};
  const std::string relative = path.substr(best->first.size());
  if (!SafeRelativePath(relative)) return {};
  return InsideFolder(best->second, relative);
}

std::string ContentTypeOf(const std::filesystem::path& file) {
  static const std::map<std::string, std::string> types = {
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},
      {".png", "image/png"},
      {".svg", "image/svg+xml"},
      {".ico", "image/x-icon"},
      {".txt", "text/plain; charset=utf-8"}};
  const auto found = types.find(file.extension().string());
  return found == types.end() ? "application/octet-stream" : found->second;
}

class WebSocketSession;

// Everything lives on the one I/O thread, except the counters and Publish.
class WebServer::Impl {
 public:
  Impl(const WebServerOptions& options, Greeting greeting, ClientMessage on_message);
  ~Impl();

  std::string address() const { return address_; }
  void Publish(const std::string& channel, WebMessage message);
  WebServerCounters Counters() const;

  // For the sessions (I/O thread).
  const WebServerOptions& options() const { return options_; }
  void Join(const std::shared_ptr<WebSocketSession>& session);
  std::string Greet() const { return greeting_(); }
  // Foxglove: the channel id of a channel (0: none), and back; the greetings.
  uint32_t FoxgloveIdOf(const std::string& channel) const;
  std::string FoxgloveChannelOf(uint32_t id) const;
  std::string FoxgloveServerInfo() const;
  std::string FoxgloveAdvertisement() const;
  std::optional<WebMessage> Latest(const std::string& channel) const;
  std::string OnClientMessage(const std::string& text) { return on_message_(text); }

  struct Counts {
    std::atomic<int64_t> clients{0}, connections{0}, accepted{0}, refused{0}, http_requests{0},
        bad_requests{0}, messages_sent{0}, bytes_sent{0}, messages_skipped{0}, client_messages{0},
        client_errors{0}, foxglove_clients{0};
  };
  Counts& counts() { return counts_; }

 private:
  void Accept();
  void OnAccept(const boost::system::error_code& error, tcp::socket socket);

  // Declared first: destroyed last, after the sessions that count in them.
  Counts counts_;
  WebServerOptions options_;
  Greeting greeting_;
  ClientMessage on_message_;
  std::map<std::string, WebMessage> latest_;
  std::vector<std::weak_ptr<WebSocketSession>> sessions_;
  asio::io_context io_{1};
  tcp::acceptor acceptor_{io_};
  std::string address_;
  std::thread thread_;
};

namespace {

// One TCP connection counted from accept to close, whichever session holds it.
class ConnectionSlot {
 public:
  explicit ConnectionSlot(WebServer::Impl::Counts& counts) : counts_(counts) {
    ++counts_.connections;
  }
  ~ConnectionSlot() { --counts_.connections; }
  ConnectionSlot(const ConnectionSlot&) = delete;
  ConnectionSlot& operator=(const ConnectionSlot&) = delete;

 private:
  WebServer::Impl::Counts& counts_;
};

}  // namespace

// A browser's WebSocket: a greeting, then the latest message of each
// channel. A Foxglove client instead gets the server's info and its
// advertised channels, then the latest of each channel it subscribed to,
// framed as that protocol's message data (op 1, subscription id, time).
class WebSocketSession : public std::enable_shared_from_this<WebSocketSession> {
 public:
  WebSocketSession(tcp::socket socket, WebServer::Impl& server,
                   std::shared_ptr<ConnectionSlot> slot, bool foxglove)
      : ws_(std::move(socket)), server_(server), slot_(std::move(slot)), foxglove_(foxglove) {}
  ~WebSocketSession() {
    if (!joined_) return;
    --server_.counts().clients;
    if (foxglove_) --server_.counts().foxglove_clients;
  }

  // (Beast reads the request during the call alone, as its examples rely on.)
  void Run(const http::request<http::string_body>& request) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    if (foxglove_) {
      ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& response) {
        response.set(http::field::sec_websocket_protocol, kFoxgloveSubprotocol);
      }));
    }
    ws_.read_message_max(static_cast<size_t>(server_.options().max_client_message_bytes));
    ws_.async_accept(request, [self = shared_from_this()](const boost::system::error_code& error) {
      self->OnAccept(error);
    });
  }

  // A channel's latest message (I/O thread): replaces an unsent one.
  void Offer(const std::string& channel, const WebMessage& message) {
    if (closed_ || Wants(channel) == 0) return;
    auto [slot, fresh] = pending_.insert_or_assign(channel, message);
    if (!fresh) ++server_.counts().messages_skipped;
    MaybeWrite();
  }

 private:
  // 0: not for this client; else its channel id (Foxglove) or 1.
  uint32_t Wants(const std::string& channel) const {
    const bool foxglove_channel = server_.FoxgloveIdOf(channel) != 0;
    if (!foxglove_) return foxglove_channel ? 0 : 1;
    const auto subscribed = subscriptions_.find(channel);
    return subscribed == subscriptions_.end() ? 0 : subscribed->second;
  }

  void OnAccept(const boost::system::error_code& error) {
    if (error) {
      ++server_.counts().client_errors;
      return;
    }
    joined_ = true;
    ++server_.counts().clients;
    if (foxglove_) {
      ++server_.counts().foxglove_clients;
      Direct(server_.FoxgloveServerInfo());
      Direct(server_.FoxgloveAdvertisement());
    } else {
      Direct(server_.Greet());
    }
    server_.Join(shared_from_this());
    Read();
  }

  void Direct(std::string text) {
    if (text.empty() || direct_.size() >= kMaxDirectMessages) return;
    direct_.push_back({"", {std::make_shared<const std::string>(std::move(text)), false}});
    MaybeWrite();
  }

  // Greetings and replies first, then the channels in turn.
  bool TakeNext(std::pair<std::string, WebMessage>* next) {
    if (!direct_.empty()) {
      *next = std::move(direct_.front());
      direct_.pop_front();
      return true;
    }
    if (pending_.empty()) return false;
    auto item = pending_.upper_bound(last_channel_);
    if (item == pending_.end()) item = pending_.begin();
    last_channel_ = item->first;
    *next = {item->first, std::move(item->second)};
    pending_.erase(item);
    return true;
  }

  // Foxglove's message data header: op 1, subscription id, time (ns), little-endian.
  void FrameFor(uint32_t subscription, int64_t utime) {
    frame_header_[0] = 1;
    for (int i = 0; i < 4; ++i)
      frame_header_[1 + i] = static_cast<uint8_t>(subscription >> (8 * i));
    const auto nanoseconds = static_cast<uint64_t>(utime) * 1000u;
    for (int i = 0; i < 8; ++i) frame_header_[5 + i] = static_cast<uint8_t>(nanoseconds >> (8 * i));
  }

  void MaybeWrite() {
    if (writing_ || closed_ || !joined_) return;
    std::pair<std::string, WebMessage> next;
    if (!TakeNext(&next)) return;
    writing_ = true;
    in_flight_ = std::move(next.second.payload);
    const bool framed = foxglove_ && !next.first.empty();
    std::array<asio::const_buffer, 2> buffers = {asio::const_buffer(), asio::buffer(*in_flight_)};
    if (framed) {
      const auto subscription = subscription_ids_.find(next.first);
      FrameFor(subscription == subscription_ids_.end() ? 0 : subscription->second,
               next.second.utime);
      buffers[0] = asio::buffer(frame_header_);
    }
    ws_.binary(framed || next.second.binary);
    ws_.async_write(
        buffers, [self = shared_from_this()](const boost::system::error_code& error, size_t bytes) {
          self->OnWrite(error, bytes);
        });
  }

  void OnWrite(const boost::system::error_code& error, size_t bytes) {
    writing_ = false;
    in_flight_.reset();
    if (error) {
      closed_ = true;
      return;
    }
    ++server_.counts().messages_sent;
    server_.counts().bytes_sent += static_cast<int64_t>(bytes);
    MaybeWrite();
  }

  void Read() {
    ws_.async_read(read_buffer_, [self = shared_from_this()](const boost::system::error_code& error,
                                                             size_t) { self->OnRead(error); });
  }

  void OnRead(const boost::system::error_code& error) {
    if (error) {
      if (error != websocket::error::closed) ++server_.counts().client_errors;
      closed_ = true;
      return;
    }
    ++server_.counts().client_messages;
    if (ws_.got_text()) {
      const std::string text = beast::buffers_to_string(read_buffer_.data());
      if (foxglove_) {
        OnFoxgloveRequest(text);
      } else {
        Direct(server_.OnClientMessage(text));
      }
    }
    read_buffer_.consume(read_buffer_.size());
    Read();
  }

  // subscribe / unsubscribe; anything else (we advertise no capabilities) is ignored.
  void OnFoxgloveRequest(const std::string& text) {
    const nlohmann::json request = nlohmann::json::parse(text, nullptr, false);
    if (!request.is_object()) return;
    const std::string op = request.value("op", "");
    if (op == "subscribe" && request.contains("subscriptions") &&
        request["subscriptions"].is_array()) {
      for (const nlohmann::json& item : request["subscriptions"]) Subscribe(item);
    } else if (op == "unsubscribe" && request.contains("subscriptionIds") &&
               request["subscriptionIds"].is_array()) {
      for (const nlohmann::json& id : request["subscriptionIds"]) {
        if (id.is_number_unsigned()) Unsubscribe(id.get<uint32_t>());
      }
    }
  }

  void Subscribe(const nlohmann::json& item) {
    if (!item.is_object() || !item.value("id", nlohmann::json()).is_number_unsigned() ||
        !item.value("channelId", nlohmann::json()).is_number_unsigned()) {
      return;
    }
    const std::string channel = server_.FoxgloveChannelOf(item["channelId"].get<uint32_t>());
    if (channel.empty()) return;
    subscriptions_[channel] = item["channelId"].get<uint32_t>();
    subscription_ids_[channel] = item["id"].get<uint32_t>();
    if (const std::optional<WebMessage> latest = server_.Latest(channel)) Offer(channel, *latest);
  }

  void Unsubscribe(uint32_t id) {
    for (auto it = subscription_ids_.begin(); it != subscription_ids_.end();) {
      if (it->second == id) {
        subscriptions_.erase(it->first);
        pending_.erase(it->first);
        it = subscription_ids_.erase(it);
      } else {
        ++it;
      }
    }
  }

  websocket::stream<beast::tcp_stream> ws_;
  WebServer::Impl& server_;
  std::shared_ptr<ConnectionSlot> slot_;
  const bool foxglove_;
  beast::flat_buffer read_buffer_;
  std::deque<std::pair<std::string, WebMessage>> direct_;  // channel "": not framed
  std::map<std::string, WebMessage> pending_;
  std::string last_channel_;
  std::shared_ptr<const std::string> in_flight_;
  std::array<uint8_t, 13> frame_header_{};
  std::map<std::string, uint32_t> subscriptions_;     // channel → channel id (Foxglove)
  std::map<std::string, uint32_t> subscription_ids_;  // channel → the client's subscription id
  bool joined_ = false;
  bool writing_ = false;
  bool closed_ = false;
};

namespace {

// HTTP requests on one connection until it closes or becomes a WebSocket.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, WebServer::Impl& server)
      : stream_(std::move(socket)),
        server_(server),
        slot_(std::make_shared<ConnectionSlot>(server.counts())) {}

  void Read() {
    const WebServerOptions& options = server_.options();
    parser_.emplace();
    parser_->header_limit(static_cast<uint32_t>(options.max_request_bytes));
    parser_->body_limit(static_cast<uint64_t>(options.max_request_bytes));
    stream_.expires_after(Millis(options.idle_timeout_s));
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](const boost::system::error_code& error, size_t) {
                       self->OnRead(error);
                     });
  }

 private:
  void OnRead(const boost::system::error_code& error) {
    if (error == http::error::end_of_stream || error == beast::error::timeout ||
        error == asio::error::connection_reset || error == asio::error::eof) {
      return Close();
    }
    if (error) {
      ++server_.counts().bad_requests;
      return Answer(Plain(http::status::bad_request, "bad request: " + error.message() + "\n"),
                    false);
    }
    http::request<http::string_body> request = parser_->release();
    if (websocket::is_upgrade(request)) return Upgrade(request);
    Answer(Respond(request), request.keep_alive());
  }

  void Upgrade(const http::request<http::string_body>& request) {
    if (request.target() != "/ws") {
      ++server_.counts().bad_requests;
      return Answer(Plain(http::status::not_found, "WebSocket only at /ws\n"), false);
    }
    const bool foxglove = std::string{request[http::field::sec_websocket_protocol]}.find(
                              kFoxgloveSubprotocol) != std::string::npos;
    stream_.expires_never();
    std::make_shared<WebSocketSession>(stream_.release_socket(), server_, slot_, foxglove)
        ->Run(request);
  }

  http::response<http::string_body> Respond(const http::request<http::string_body>& request) {
    if (request.method() != http::verb::get && request.method() != http::verb::head) {
      ++server_.counts().bad_requests;
      return Plain(http::status::method_not_allowed, "only GET and HEAD\n");
    }
    const std::filesystem::path file =
        StaticFileFor(server_.options().folders, std::string{request.target()});
    if (file.empty()) {
      ++server_.counts().bad_requests;
      return Plain(http::status::not_found, "not found\n");
    }
    ++server_.counts().http_requests;
    http::response<http::string_body> response{http::status::ok, 11};
    response.set(http::field::content_type, ContentTypeOf(file));
    response.set(http::field::cache_control, "no-cache");
    response.body() = ReadWholeFile(file);
    response.prepare_payload();
    if (request.method() == http::verb::head) response.body().clear();
    return response;
  }

  static http::response<http::string_body> Plain(http::status status, std::string text) {
    http::response<http::string_body> response{status, 11};
    response.set(http::field::content_type, "text/plain; charset=utf-8");
    response.body() = std::move(text);
    response.prepare_payload();
    return response;
  }

  void Answer(http::response<http::string_body> response, bool keep_alive) {
    response.keep_alive(keep_alive);
    auto owned = std::make_shared<http::response<http::string_body>>(std::move(response));
    stream_.expires_after(Millis(server_.options().idle_timeout_s));
    http::async_write(stream_, *owned,
                      [self = shared_from_this(), owned, keep_alive](
                          const boost::system::error_code& error, size_t) {
                        if (error || !keep_alive) return self->Close();
                        self->Read();
                      });
  }

  void Close() {
    boost::system::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
  }

  beast::tcp_stream stream_;
  WebServer::Impl& server_;
  std::shared_ptr<ConnectionSlot> slot_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
};

}  // namespace

WebServer::Impl::Impl(const WebServerOptions& options, Greeting greeting, ClientMessage on_message)
    : options_(options), greeting_(std::move(greeting)), on_message_(std::move(on_message)) {
  if (options_.listen_fd >= 0) {
    sockaddr_storage bound{};
    socklen_t length = sizeof(bound);
    const bool v6 =
        getsockname(options_.listen_fd, reinterpret_cast<sockaddr*>(&bound), &length) == 0 &&
        bound.ss_family == AF_INET6;
    acceptor_.assign(v6 ? tcp::v6() : tcp::v4(), options_.listen_fd);
  } else {
    const tcp::endpoint endpoint = ParseEndpoint(options_.listen);
    boost::system::error_code error;
    acceptor_.open(endpoint.protocol(), error);
    if (!error) acceptor_.set_option(asio::socket_base::reuse_address(true), error);
    if (!error) acceptor_.bind(endpoint, error);
    if (!error) acceptor_.listen(asio::socket_base::max_listen_connections, error);
    if (error) {
      throw std::runtime_error("cannot listen on " + options_.listen + ": " + error.message());
    }
  }
  const tcp::endpoint local = acceptor_.local_endpoint();
  address_ = (local.address().is_v6() ? "[" + local.address().to_string() + "]"
                                      : local.address().to_string()) +
             ":" + std::to_string(local.port());
  Accept();
  thread_ = std::thread([this] { io_.run(); });
}

WebServer::Impl::~Impl() {
  io_.stop();
  if (thread_.joinable()) thread_.join();
}

void WebServer::Impl::Accept() {
  acceptor_.async_accept(io_, [this](const boost::system::error_code& error, tcp::socket socket) {
    OnAccept(error, std::move(socket));
  });
}

void WebServer::Impl::OnAccept(const boost::system::error_code& error, tcp::socket socket) {
  if (error == asio::error::operation_aborted) return;
  if (!error) {
    ++counts_.accepted;
    if (counts_.connections.load() >= options_.max_connections) {
      ++counts_.refused;
      boost::system::error_code ignored;
      socket.close(ignored);
    } else {
      std::make_shared<HttpSession>(std::move(socket), *this)->Read();
    }
  }
  Accept();
}

void WebServer::Impl::Join(const std::shared_ptr<WebSocketSession>& session) {
  std::erase_if(sessions_, [](const std::weak_ptr<WebSocketSession>& s) { return s.expired(); });
  sessions_.push_back(session);
  for (const auto& [channel, message] : latest_) session->Offer(channel, message);
}

void WebServer::Impl::Publish(const std::string& channel, WebMessage message) {
  asio::post(io_, [this, channel, message = std::move(message)] {
    latest_[channel] = message;
    for (const std::weak_ptr<WebSocketSession>& weak : sessions_) {
      if (const std::shared_ptr<WebSocketSession> session = weak.lock()) {
        session->Offer(channel, message);
      }
    }
  });
}

WebServerCounters WebServer::Impl::Counters() const {
  return {counts_.clients.load(),          counts_.connections.load(),
          counts_.accepted.load(),         counts_.refused.load(),
          counts_.http_requests.load(),    counts_.bad_requests.load(),
          counts_.messages_sent.load(),    counts_.bytes_sent.load(),
          counts_.messages_skipped.load(), counts_.client_messages.load(),
          counts_.client_errors.load(),    counts_.foxglove_clients.load()};
}

uint32_t WebServer::Impl::FoxgloveIdOf(const std::string& channel) const {
  for (size_t i = 0; i < options_.foxglove.size(); ++i) {
    if (options_.foxglove[i].channel == channel) return static_cast<uint32_t>(i + 1);
  }
  return 0;
}

std::string WebServer::Impl::FoxgloveChannelOf(uint32_t id) const {
  return id >= 1 && id <= options_.foxglove.size() ? options_.foxglove[id - 1].channel : "";
}

std::string WebServer::Impl::FoxgloveServerInfo() const {
  return nlohmann::json{{"op", "serverInfo"},
                        {"name", options_.name},
                        {"capabilities", nlohmann::json::array()},
                        {"supportedEncodings", nlohmann::json::array()},
                        {"metadata", nlohmann::json::object()},
                        {"sessionId", std::to_string(reinterpret_cast<uintptr_t>(this))}}
      .dump();
}

std::string WebServer::Impl::FoxgloveAdvertisement() const {
  nlohmann::json channels = nlohmann::json::array();
  for (size_t i = 0; i < options_.foxglove.size(); ++i) {
    const FoxgloveChannel& channel = options_.foxglove[i];
    channels.push_back({{"id", i + 1},
                        {"topic", channel.topic},
                        {"encoding", "json"},
                        {"schemaName", channel.schema_name},
                        {"schema", channel.schema},
                        {"schemaEncoding", "jsonschema"}});
  }
  return nlohmann::json{{"op", "advertise"}, {"channels", channels}}.dump();
}

std::optional<WebMessage> WebServer::Impl::Latest(const std::string& channel) const {
  const auto found = latest_.find(channel);
  if (found == latest_.end()) return std::nullopt;
  return found->second;
}

WebServer::WebServer(const WebServerOptions& options, Greeting greeting, ClientMessage on_message)
    : impl_(std::make_unique<Impl>(options, std::move(greeting), std::move(on_message))) {}

WebServer::~WebServer() = default;

std::string WebServer::address() const { return impl_->address(); }

void WebServer::Publish(const std::string& channel, WebMessage message) {
  impl_->Publish(channel, std::move(message));
}

WebServerCounters WebServer::Counters() const { return impl_->Counters(); }

}  // namespace shapesense
