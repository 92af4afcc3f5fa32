#pragma once
// --control [ADDR:]PORT: the control API and the controller page on render rank 0, over HTTP
// (docs/service.md, "Steering the wall"; docs/security.md, "The control API"). Debian's
// libmicrohttpd serves it from two event-loop threads of its own, so slow or many clients never
// stall each other or a frame: at most 256 connections (128 from one address), and every request
// (or idle keep-alive wait) must be over within 5 s of its start, however slowly its bytes
// arrive, or its connection is cut.
//
// Who may ask and what they may do is decided by apps/ControlRequests.h (a secret always,
// loopback included; a Host allow-list; Origin and Content-Type for the page's changes); the
// routes are apps/ControlApi.h and apps/PageRoutes.h. The secret comes from
// apps/ControlSecret.h: a file, the environment, or generated and printed as the address to open.
#include <memory>
#include <string>
#include <vector>

#include "apps/ControlRequests.h"
#include "apps/ControlSecret.h"

namespace app {

class ControlServer {
 public:
  // Binds `address` ([ADDR:]PORT; port 0 picks a free one). `hosts`: more names a Host header
  // may carry (--control-host). Throws std::runtime_error naming the address when it cannot be
  // parsed or bound (a port in use).
  ControlServer(const std::string& address, ControlSecret secret, std::vector<std::string> hosts);
  ~ControlServer();  // stops serving
  ControlServer(const ControlServer&) = delete;
  ControlServer& operator=(const ControlServer&) = delete;

  const std::string& host() const;  // as bound ("0.0.0.0" for every interface)
  int port() const;
  const ControlSecret& secret() const;

  // The routes, to add before start().
  ControlRequests& requests();
  // Serves until stop() or destruction.
  void start();
  void stop();

  // What to print once: the address to open, with the token when it was generated for this run
  // (a token from a file or the environment is not repeated in the log).
  std::string startLine() const;
  // The page's address for others to link (no token): http://HOST:PORT/, `thisHost` (this host's
  // name) for a server on every interface.
  std::string pageAddress(const std::string& thisHost) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace app
