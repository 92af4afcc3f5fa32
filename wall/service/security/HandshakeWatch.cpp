#include "wall/service/security/HandshakeWatch.h"

#include <atomic>
#include <cstring>

namespace wall::service {
namespace {
// Handshakes that break off before the peer is ours: a reconnect is tried every 100 ms, so this
// many in a row is a mismatch, not bad luck.
constexpr int kBrokenOff = 3;
std::atomic<std::uint64_t> watches{0};
}  // namespace

HandshakeWatch::HandshakeWatch(zmq::context_t& context, zmq::socket_t& socket)
    : socket_(socket), events_(context, zmq::socket_type::pair) {
  const std::string endpoint = "inproc://dfbwall-handshake-" + std::to_string(++watches);
  const int wanted = ZMQ_EVENT_HANDSHAKE_SUCCEEDED | ZMQ_EVENT_HANDSHAKE_FAILED_AUTH |
                     ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL | ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL |
                     ZMQ_EVENT_DISCONNECTED;
  if (zmq_socket_monitor(socket.handle(), endpoint.c_str(), wanted) != 0) throw zmq::error_t();
  events_.set(zmq::sockopt::linger, 0);
  events_.connect(endpoint);
}

HandshakeWatch::~HandshakeWatch() { zmq_socket_monitor(socket_.handle(), nullptr, 0); }

zmq::pollitem_t HandshakeWatch::pollItem() { return {events_.handle(), 0, ZMQ_POLLIN, 0}; }

HandshakeWatch::State HandshakeWatch::poll() {
  zmq::message_t event, address;
  while (events_.recv(event, zmq::recv_flags::dontwait)) {
    if (event.more()) (void)events_.recv(address, zmq::recv_flags::dontwait);
    if (event.size() < 6) continue;
    std::uint16_t id = 0;
    std::uint32_t value = 0;
    std::memcpy(&id, event.data(), 2);
    std::memcpy(&value, static_cast<const char*>(event.data()) + 2, 4);
    switch (id) {
      case ZMQ_EVENT_HANDSHAKE_SUCCEEDED:
        state_ = State::Succeeded;
        brokenOff_ = 0;
        break;
      case ZMQ_EVENT_HANDSHAKE_FAILED_AUTH:
        state_ = State::Refused;
        problem_ = "it refused this token (status " + std::to_string(value) + ")";
        break;
      case ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL:
      case ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL:
      case ZMQ_EVENT_DISCONNECTED:
        if (state_ == State::Succeeded && id == ZMQ_EVENT_DISCONNECTED) {
          state_ = State::Pending;  // a link that was up went down: the next handshake decides
          break;
        }
        if (state_ == State::Pending && ++brokenOff_ >= kBrokenOff) {
          state_ = State::Failed;
          problem_ =
              "the handshake broke off " + std::to_string(brokenOff_) +
              " times: it does not hold the key --server-key names, or one side uses CURVE "
              "and the other does not (serve --curve DIR needs --server-key DIR/wall-public.key "
              "on jobs, relays and joining processes)";
        }
        break;
      default:
        break;
    }
  }
  return state_;
}

}  // namespace wall::service
