#pragma once
// What the wall service needs of ZeroMQ (cppzmq): messages that hand a messaging::Bytes over
// without a copy, socket options every link of ours sets, endpoints and the address a process
// advertises, and a way to wake a thread that waits in zmq::poll from any other thread.
//
// Why ZeroMQ: it frames messages (a length is never ours to trust: ZMQ_MAXMSGSIZE drops a peer
// that announces more before anything is allocated), queues sends without blocking the render
// threads (high-water marks), reconnects, sends heartbeats so a dead peer or a cut link closes
// the connection, and authenticates and encrypts at the handshake (PLAIN or CURVE with a ZAP
// handler: wall/service/security/), so a peer without the wall's token never gets a message
// through. Sockets are not thread-safe: each is used by one thread, or under a mutex.
#include <zmq.hpp>

#include <string>

#include "messaging/Compression.h"

namespace wall::service {

// A message owning `bytes` (no copy).
zmq::message_t toMessage(messaging::Bytes&& bytes);
// Which end of its connections a socket is: one that binds and takes peers, or one that dials.
enum class Side { accepts, dials };
// Limits and liveness every socket of ours gets: a message part over `maxMessageBytes` (what
// the socket carries: Protocol.h) closes the connection; one that has not finished its handshake
// after a few seconds too. A dialing socket sends heartbeats and closes a connection silent for
// `deadPeerMs`; an accepting one answers them, closes a connection whose peer stops sending
// them (their time-to-live is `deadPeerMs`), and TCP keepalives find a dead host that never sent
// one. An accepting socket never sends heartbeats of its own: libzmq 4.3.4 aborts the process
// when its heartbeat timer fires on a connection reset while that peer's queue was full
// (docs/security.md, "A flooding peer and libzmq's heartbeats").
// `lingerMs`: how long closing the socket waits for messages still queued (a job's last pieces
// must reach the wall after its rank is done; the wall's own sockets wait for nobody).
void configureSocket(zmq::socket_t& socket, Side side, int deadPeerMs, std::size_t maxMessageBytes,
                     int lingerMs = 0);
// A message larger than the receiver's part cap goes as several parts of `partBytes`; the
// receiver joins them (receiveJoined).
void sendInParts(zmq::socket_t& socket, const messaging::Bytes& bytes, std::size_t partBytes);
// After `first` was received: the rest of its parts, joined to it, as long as the whole stays
// within `maxBytes` (false: too large, the parts are read and dropped).
bool receiveJoined(zmq::socket_t& socket, zmq::message_t& first, std::size_t maxBytes);
// "HOST:PORT" or "PORT" (then 127.0.0.1) -> "tcp://HOST:PORT"; throws base::Error naming
// `option` on anything else.
std::string tcpEndpoint(const std::string& address, const std::string& option);
// The host part of an address as `tcpEndpoint` reads it.
std::string hostOf(const std::string& address);
bool isLoopback(const std::string& host);
// What other hosts should dial to reach this process: the listen host when it is a specific
// address, otherwise this host's first non-loopback IPv4 address (127.0.0.1 when it has none).
std::string advertisedHost(const std::string& listenHost);
// `advertise` (an --advertise HOST) when a socket bound to `bindHost` is reachable there: the
// same address, or any of this host's addresses when it binds them all (0.0.0.0); throws
// base::Error naming `option` otherwise. A name is resolved to its IPv4 addresses.
std::string checkAdvertised(const std::string& advertise, const std::string& bindHost,
                            const std::string& option);
// The endpoint a socket bound to, with the real port ("tcp://0.0.0.0:41234").
std::string lastEndpoint(zmq::socket_t& socket);
// The port of a "tcp://HOST:PORT" endpoint.
int portOf(const std::string& endpoint);

// An eventfd: notify() from any thread makes it readable; pollItem() goes in a zmq::poll list.
class Waker {
 public:
  Waker();
  ~Waker();
  Waker(const Waker&) = delete;
  Waker& operator=(const Waker&) = delete;
  void notify();
  void drain();
  zmq::pollitem_t pollItem() const;

 private:
  int fd_ = -1;
};

}  // namespace wall::service
