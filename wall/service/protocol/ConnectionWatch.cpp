#include "wall/service/protocol/ConnectionWatch.h"

#include <atomic>
#include <cstdint>
#include <cstring>

namespace wall::service {
namespace {
std::atomic<std::uint64_t> watches{0};
}  // namespace

ConnectionWatch::ConnectionWatch(zmq::context_t& context, zmq::socket_t& router)
    : router_(router), events_(context, zmq::socket_type::pair) {
  const std::string endpoint = "inproc://dfbwall-connections-" + std::to_string(++watches);
  if (zmq_socket_monitor(router.handle(), endpoint.c_str(), ZMQ_EVENT_DISCONNECTED) != 0)
    throw zmq::error_t();
  events_.set(zmq::sockopt::linger, 0);
  // No high-water mark: libzmq's I/O thread would wait on a full monitor queue (one event per
  // closed connection; the desk reads them every turn).
  events_.set(zmq::sockopt::rcvhwm, 0);
  events_.connect(endpoint);
}

ConnectionWatch::~ConnectionWatch() { zmq_socket_monitor(router_.handle(), nullptr, 0); }

zmq::pollitem_t ConnectionWatch::pollItem() { return {events_.handle(), 0, ZMQ_POLLIN, 0}; }

void ConnectionWatch::heard(const std::string& peer, const zmq::message_t& part) {
  // ZMQ_SRCFD: deprecated in libzmq's header for ZMQ_ROUTER_NOTIFY's sake, still kept in 4.3.
  const int fd = zmq_msg_get(part.handle(), ZMQ_SRCFD);
  if (fd < 0) return;  // not from a TCP connection
  const auto known = fdOf_.find(peer);
  if (known != fdOf_.end() && known->second == fd) return;
  // A descriptor new to this peer: first what closed so far (its old owner, perhaps).
  readEvents();
  if (const auto was = fdOf_.find(peer); was != fdOf_.end()) peerOn_.erase(was->second);
  if (const auto owner = peerOn_.find(fd); owner != peerOn_.end()) {
    // Reused while its close is not reported yet: the old connection is closed all the same.
    closed_.push_back(owner->second);
    fdOf_.erase(owner->second);
  }
  peerOn_[fd] = peer;
  fdOf_[peer] = fd;
}

std::vector<std::string> ConnectionWatch::closed() {
  readEvents();
  std::vector<std::string> out;
  out.swap(closed_);
  return out;
}

void ConnectionWatch::readEvents() {
  zmq::message_t event, address;
  while (events_.recv(event, zmq::recv_flags::dontwait)) {
    if (event.more()) (void)events_.recv(address, zmq::recv_flags::dontwait);
    if (event.size() < 6) continue;
    std::uint16_t id = 0;
    std::int32_t fd = -1;
    std::memcpy(&id, event.data(), 2);
    std::memcpy(&fd, static_cast<const char*>(event.data()) + 2, 4);
    if (id != ZMQ_EVENT_DISCONNECTED) continue;
    const auto owner = peerOn_.find(fd);
    if (owner == peerOn_.end()) continue;  // a connection that never got a message through
    closed_.push_back(owner->second);
    fdOf_.erase(owner->second);
    peerOn_.erase(owner);
  }
}

}  // namespace wall::service
