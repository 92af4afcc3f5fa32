#include "wall/service/protocol/Zmq.h"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <set>
#include <vector>

#include "base/Error.h"
#include "wall/service/protocol/Protocol.h"

namespace wall::service {

zmq::message_t toMessage(messaging::Bytes&& bytes) {
  auto* owned = new messaging::Bytes(std::move(bytes));
  return zmq::message_t(
      owned->data(), owned->size(),
      [](void*, void* hint) { delete static_cast<messaging::Bytes*>(hint); }, owned);
}

void configureSocket(zmq::socket_t& socket, Side side, int deadPeerMs, std::size_t maxMessageBytes,
                     int lingerMs) {
  socket.set(zmq::sockopt::linger, lingerMs);
  socket.set(zmq::sockopt::maxmsgsize, static_cast<std::int64_t>(maxMessageBytes));
  if (side == Side::dials) {
    socket.set(zmq::sockopt::heartbeat_ivl, std::max(100, deadPeerMs / 4));
    socket.set(zmq::sockopt::heartbeat_timeout, deadPeerMs);
    socket.set(zmq::sockopt::heartbeat_ttl, deadPeerMs);
  } else {
    // Keepalive probes start after half the timeout of silence, one a second (whole seconds).
    const int halfSeconds = std::max(1, deadPeerMs / 2000);
    socket.set(zmq::sockopt::tcp_keepalive, 1);
    socket.set(zmq::sockopt::tcp_keepalive_idle, halfSeconds);
    socket.set(zmq::sockopt::tcp_keepalive_intvl, 1);
    socket.set(zmq::sockopt::tcp_keepalive_cnt, halfSeconds);
  }
  // A handshake takes milliseconds; a peer that dawdles in it holds a connection for nothing.
  socket.set(zmq::sockopt::handshake_ivl, std::min(deadPeerMs, 10000));
}

void sendInParts(zmq::socket_t& socket, const messaging::Bytes& bytes, std::size_t partBytes) {
  for (std::size_t at = 0; at < bytes.size() || at == 0; at += partBytes) {
    const std::size_t n = std::min(partBytes, bytes.size() - at);
    const bool last = at + n >= bytes.size();
    // Once the first part is taken, ZeroMQ takes the others: a message goes whole or not at all.
    if (!socket.send(zmq::buffer(bytes.data() + at, n),
                     last ? zmq::send_flags::dontwait
                          : zmq::send_flags::dontwait | zmq::send_flags::sndmore))
      return;
    if (last) break;
  }
}

bool receiveJoined(zmq::socket_t& socket, zmq::message_t& first, std::size_t maxBytes) {
  if (!first.more()) return first.size() <= maxBytes;
  messaging::Bytes joined(first.data<std::byte>(), first.data<std::byte>() + first.size());
  bool fits = joined.size() <= maxBytes;
  zmq::message_t part;
  bool more = true;
  while (more && socket.recv(part, zmq::recv_flags::dontwait)) {
    more = part.more();
    fits = fits && joined.size() + part.size() <= maxBytes;
    if (fits)
      joined.insert(joined.end(), part.data<std::byte>(), part.data<std::byte>() + part.size());
  }
  if (!fits) return false;
  first = toMessage(std::move(joined));
  return true;
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

namespace {
// This host's IPv4 addresses, in the order of its interfaces.
std::vector<std::string> localAddresses() {
  std::vector<std::string> found;
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return found;
  for (ifaddrs* a = list; a; a = a->ifa_next) {
    if (!a->ifa_addr || a->ifa_addr->sa_family != AF_INET) continue;
    char text[INET_ADDRSTRLEN];
    const auto* in = reinterpret_cast<const sockaddr_in*>(a->ifa_addr);
    if (inet_ntop(AF_INET, &in->sin_addr, text, sizeof text)) found.emplace_back(text);
  }
  freeifaddrs(list);
  return found;
}

// The IPv4 addresses `host` names (itself when it is one).
std::set<std::string> addressesOf(const std::string& host) {
  std::set<std::string> found;
  addrinfo hints{};
  hints.ai_family = AF_INET;
  addrinfo* list = nullptr;
  if (getaddrinfo(host.c_str(), nullptr, &hints, &list) != 0) return found;
  for (addrinfo* a = list; a; a = a->ai_next) {
    char text[INET_ADDRSTRLEN];
    const auto* in = reinterpret_cast<const sockaddr_in*>(a->ai_addr);
    if (inet_ntop(AF_INET, &in->sin_addr, text, sizeof text)) found.insert(text);
  }
  freeaddrinfo(list);
  return found;
}
}  // namespace

std::string advertisedHost(const std::string& listenHost) {
  if (listenHost != "0.0.0.0" && listenHost != "*" && !listenHost.empty()) return listenHost;
  for (const std::string& address : localAddresses())
    if (!isLoopback(address)) return address;
  return "127.0.0.1";
}

std::string checkAdvertised(const std::string& advertise, const std::string& bindHost,
                            const std::string& option) {
  if (advertise.empty() || advertise.find_first_of(" /\\\"':") != std::string::npos)
    throw base::Error(option + " '" + advertise + "': expected a host name or IPv4 address");
  const std::set<std::string> named = addressesOf(advertise);
  if (named.empty())
    throw base::Error(option + " " + advertise + ": no IPv4 address has that name");
  const bool everywhere = bindHost == "0.0.0.0" || bindHost == "*" || bindHost.empty();
  std::set<std::string> bound = everywhere ? std::set<std::string>{} : addressesOf(bindHost);
  if (everywhere)
    for (std::string& a : localAddresses()) bound.insert(std::move(a));
  for (const std::string& a : named)
    if (bound.count(a)) return advertise;
  std::string list;
  for (const std::string& a : bound) list += (list.empty() ? "" : ", ") + a;
  throw base::Error(option + " " + advertise + ": this process does not listen there (it " +
                    (everywhere ? "listens on this host's addresses: " : "listens on ") +
                    (everywhere ? list : bindHost) + ")");
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
