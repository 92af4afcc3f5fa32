#pragma once
// Which connections of a ROUTER socket closed, named by the routing id their messages came
// under: a job whose connection closes (its rank 0 died, its relay stopped) is gone at once,
// instead of when its silence outlasts the wall's timeout.
//
// libzmq says so itself with ZMQ_ROUTER_NOTIFY, a draft API that Debian's libzmq 4.3.4 is built
// without; so a socket monitor reports each closed connection's file descriptor
// (ZMQ_EVENT_DISCONNECTED), and each message received tells the descriptor it came on
// (ZMQ_SRCFD). A descriptor is reused once closed: libzmq reports the close before the
// descriptor can be reused, and heard() reads the reports before it takes a descriptor for a
// new routing id, so an old close is never pinned on the new connection.
#include <zmq.hpp>

#include <string>
#include <unordered_map>
#include <vector>

namespace wall::service {

class ConnectionWatch {
 public:
  // Before `router` binds or connects; `router` must outlive the watch.
  ConnectionWatch(zmq::context_t& context, zmq::socket_t& router);
  ~ConnectionWatch();
  ConnectionWatch(const ConnectionWatch&) = delete;
  ConnectionWatch& operator=(const ConnectionWatch&) = delete;

  // A message from `peer` (its routing id) was received on the router: `part` is any part of it.
  void heard(const std::string& peer, const zmq::message_t& part);
  // The peers heard from whose connections closed since the last call, oldest first.
  std::vector<std::string> closed();
  // For zmq::poll: readable when a connection closed.
  zmq::pollitem_t pollItem();

 private:
  void readEvents();

  zmq::socket_t& router_;
  zmq::socket_t events_;
  std::unordered_map<int, std::string> peerOn_;  // descriptor -> routing id
  std::unordered_map<std::string, int> fdOf_;    // routing id -> descriptor
  std::vector<std::string> closed_;
};

}  // namespace wall::service
