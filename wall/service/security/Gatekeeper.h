#pragma once
// The ZAP handler of one ZeroMQ context (ZeroMQ RFC 27): the thread that vets every peer of the
// context's server sockets (wall/service/security/Credentials.h) at the handshake, before a
// single message of theirs reaches the program. It admits a PLAIN peer whose password is the
// token, or a CURVE peer whose public key is the token's (clientKeys); it refuses everyone else,
// and says so in the log, once per address and at most a bounded number of lines.
//
// Construct it before the context's first server socket binds; destroy it before the context.
#include <zmq.hpp>

#include <atomic>
#include <functional>
#include <set>
#include <string>
#include <thread>

#include "wall/service/security/Credentials.h"

namespace wall::service {

class Gatekeeper {
 public:
  using Log = std::function<void(const std::string&)>;
  Gatekeeper(zmq::context_t& context, const Credentials& credentials, Log log);
  ~Gatekeeper();
  Gatekeeper(const Gatekeeper&) = delete;
  Gatekeeper& operator=(const Gatekeeper&) = delete;

  // Handshakes refused so far.
  std::uint64_t refused() const { return refused_; }

 private:
  void run();
  bool admits(const std::string& mechanism, const std::vector<zmq::message_t>& credentials) const;

  zmq::socket_t socket_;
  std::string token_, clientKey_;
  Log log_;
  std::set<std::string> logged_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> refused_{0};
  std::thread thread_;
};

}  // namespace wall::service
