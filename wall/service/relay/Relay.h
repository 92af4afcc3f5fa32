#pragma once
// `dfbwall relay`: one process that render jobs connect to instead of the wall (docs/service.md, "A
// wall that stays up"), for compute nodes that cannot reach the wall's network; several may run,
// one per gateway. It forwards without decoding pieces:
//
//  - who gets in: the relay's sockets admit only peers with the wall's token, at the handshake
//    (wall/service/security/Gatekeeper.h), so a stranger holds nothing here; its own links to
//    the wall present the same token (and pin the wall's key with CURVE). One peer address holds
//    at most a few job connections, so no host takes every slot;
//  - the directory link: every job connection on the relay's --listen socket gets a connection
//    of its own to the wall's directory socket, so the wall sees each job as it would directly
//    (its hello decides; refusals and queue places come back through); when a job's connection
//    closes, so does its link to the wall, and the wall drops the job at once. The
//    wall's Directory and Roster reach the job rewritten (wall/service/relay/RelayRoutes.h): each
//    wall process's endpoint becomes the relay's piece endpoint for it;
//  - the piece path: per wall process a socket of the relay's (its endpoint in the rewritten
//    directory) and a connection to that wall process (reconnected when a Roster names a new
//    endpoint). Batches of a session the wall gave a job through this relay are forwarded as
//    whole messages, never copied or decoded; anything else is dropped and logged once per
//    connection and problem. A wall process that takes its pieces slowly holds back only its
//    own socket (the relay stops reading it), so memory stays bounded and the others go on.
//
// One thread does it all; ZeroMQ's I/O thread moves the bytes.
#include <chrono>
#include <functional>
#include <memory>
#include <string>

#include "wall/service/security/Credentials.h"

namespace wall::service {

struct RelayOptions {
  std::string listen;  // [ADDR:]PORT for jobs (default address 127.0.0.1)
  std::string wall;    // HOST:PORT of the wall's directory (serve --listen)
  // The wall's token: what jobs must present here and the relay presents to the wall; with a
  // key pair the relay's sockets are CURVE servers, with a server key its links to the wall
  // are CURVE clients pinning it.
  Credentials credentials;
  std::chrono::milliseconds timeout{60000};  // a job silent this long is forgotten
  // Polled a few times a second; true stops the relay.
  std::function<bool()> stopRequested;
  std::function<void(const std::string&)> log;        // one line to the log
  std::function<void(const std::string&)> jobRecord;  // one JSON line per job (--stats)
};

class Relay {
 public:
  // Binds the listen socket; throws base::Error on a bad address or a port in use.
  explicit Relay(RelayOptions options);
  ~Relay();
  Relay(const Relay&) = delete;
  Relay& operator=(const Relay&) = delete;

  // "HOST:PORT" that jobs pass to --connect.
  std::string address() const;
  // Forwards until stopRequested() says so.
  void run();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace wall::service
