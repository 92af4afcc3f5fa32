#include "wall/service/protocol/Zmq.h"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cstdint>

#include "base/Error.h"
#include "wall/service/protocol/Protocol.h"

namespace wall::service {

zmq::message_t toMessage(messaging::Bytes&& bytes) {
  auto* owned = new messaging::Bytes(std::move(bytes));
  return zmq::message_t(
      owned->data(), owned->size(),
      [](void*, void* hint) { delete static_cast<messaging::Bytes*>(hint); }, owned);
}

void configureSocket(zmq::socket_t& socket, int deadPeerMs, int lingerMs) {
  socket.set(zmq::sockopt::linger, lingerMs);
  socket.set(zmq::sockopt::maxmsgsize, static_cast<std::int64_t>(kMaxMessageBytes));
  socket.set(zmq::sockopt::heartbeat_ivl, std::max(100, deadPeerMs / 4));
  socket.set(zmq::sockopt::heartbeat_timeout, deadPeerMs);
  socket.set(zmq::sockopt::heartbeat_ttl, deadPeerMs);
  socket.set(zmq::sockopt::handshake_ivl, deadPeerMs);
}

std::string hostOf(const std::string& address) {
  const size_t colon = address.rfind(':');
  return colon == std::string::npos ? "127.0.0.1" : address.substr(0, colon);
}

std::string tcpEndpoint(const std::string& address, const std::string& option) {
  const size_t colon = address.rfind(':');
  const std::string host = hostOf(address);
  const std::string port = colon == std::string::npos ? address : address.substr(colon + 1);
  bool digits = !port.empty() && port.size() <= 5;
  for (char c : port) digits = digits && c >= '0' && c <= '9';
  if (!digits || std::stoi(port) > 65535 || host.empty() ||
      host.find_first_of(" /\\\"'") != std::string::npos)
    throw base::Error(option + " '" + address + "': expected [HOST:]PORT, e.g. 7000 or wall0:7000");
  return "tcp://" + host + ":" + port;
}

bool isLoopback(const std::string& host) {
  return host == "localhost" || host.rfind("127.", 0) == 0 || host == "::1";
}

std::string advertisedHost(const std::string& listenHost) {
  if (listenHost != "0.0.0.0" && listenHost != "*" && !listenHost.empty()) return listenHost;
  std::string found = "127.0.0.1";
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return found;
  for (ifaddrs* a = list; a; a = a->ifa_next) {
    if (!a->ifa_addr || a->ifa_addr->sa_family != AF_INET) continue;
    char text[INET_ADDRSTRLEN];
    const auto* in = reinterpret_cast<const sockaddr_in*>(a->ifa_addr);
    if (!inet_ntop(AF_INET, &in->sin_addr, text, sizeof text)) continue;
    if (isLoopback(text)) continue;
    found = text;
    break;
  }
  freeifaddrs(list);
  return found;
}

std::string lastEndpoint(zmq::socket_t& socket) { return socket.get(zmq::sockopt::last_endpoint); }

int portOf(const std::string& endpoint) {
  const size_t colon = endpoint.rfind(':');
  return colon == std::string::npos ? 0 : std::stoi(endpoint.substr(colon + 1));
}

Waker::Waker() : fd_(eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (fd_ < 0) throw base::Error("eventfd failed");
}
Waker::~Waker() { close(fd_); }
void Waker::notify() {
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = write(fd_, &one, sizeof one);
}
void Waker::drain() {
  std::uint64_t value;
  [[maybe_unused]] const ssize_t n = read(fd_, &value, sizeof value);
}
zmq::pollitem_t Waker::pollItem() const { return {nullptr, fd_, ZMQ_POLLIN, 0}; }

}  // namespace wall::service
