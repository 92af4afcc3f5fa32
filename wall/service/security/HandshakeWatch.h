#pragma once
// What became of a client socket's handshakes (a ZeroMQ socket monitor): a peer that refuses
// our credentials, or one we cannot complete a handshake with (another CURVE key than the one
// pinned, CURVE on one side only), is reported at once instead of libzmq retrying in silence
// until a timeout.
#include <zmq.hpp>

#include <string>

namespace wall::service {

class HandshakeWatch {
 public:
  enum class State { Pending, Succeeded, Refused, Failed };
  // Before socket.connect; `socket` must live as long as the watch.
  HandshakeWatch(zmq::context_t& context, zmq::socket_t& socket);
  ~HandshakeWatch();
  HandshakeWatch(const HandshakeWatch&) = delete;
  HandshakeWatch& operator=(const HandshakeWatch&) = delete;

  // Reads the events so far without waiting. Refused: the peer's gatekeeper refused the token.
  // Failed: several handshakes in a row broke off (keys or mechanisms that do not match).
  // Succeeded stays until a later failure.
  State poll();
  // For zmq::poll: readable when there are events.
  zmq::pollitem_t pollItem();
  // Why, for State::Refused or Failed: one line, e.g. "the wall refused this token".
  std::string problem() const { return problem_; }

 private:
  zmq::socket_t& socket_;
  zmq::socket_t events_;
  State state_ = State::Pending;
  int brokenOff_ = 0;
  std::string problem_;
};

}  // namespace wall::service
