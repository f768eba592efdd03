#pragma once

// A listening TCP socket made by one process for another: the demo makes
// the web monitor's in the host's network before it moves into a private
// namespace, and hands it over as systemd would (ChildOptions::listen_socket),
// so that a browser on the host reaches a monitor inside the namespace.
#include <string>

namespace shapesense {

// Binds and listens on "IP:PORT" (port 0: any free one). Throws
// std::runtime_error naming the address and why (e.g. in use).
int OpenListeningSocket(const std::string& address);

// "127.0.0.1:8080", the address the socket is bound to.
std::string ListeningAddress(int socket);

}  // namespace shapesense
