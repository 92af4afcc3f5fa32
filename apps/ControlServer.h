#pragma once
// --control [ADDR:]PORT: the JSON-over-HTTP control API on render rank 0 (docs/service.md,
// "Steering the wall"). Debian's cpp-httplib serves it on two threads of its own; handlers only
// read the status board and queue steering requests, so a slow or hostile client never stalls a
// frame.
//
//   GET  /api/status    frame, fps, spp, camera, displays, renderer, errors
//   POST /api/camera    {"position", "look_at", "up", "fov"} (any subset), "orbit", "pan", "dolly"
//   POST /api/settings  {"exposure", "spp", "max_depth", "transfer_function", "opacity_scale"}
//   POST /api/capture   every display captures the next frame to the --capture folder
//   POST /api/stop      graceful stop: statistics and captures written, exit 0
//
// Anything but a loopback address needs a token (--control-token, or one generated and
// printed); with a token every request must carry it (Authorization: Bearer TOKEN, or
// ?token=TOKEN for a browser), else 401. A POST without a body (even without Content-Length, as
// `curl -X POST` sends it) is taken as {}. Malformed JSON, unknown fields, NaN, values out of
// range: 400 with a message; the wall keeps running.
#include <functional>
#include <memory>
#include <string>

namespace app {

class RunControl;
class StatusBoard;
class Steering;
struct Job;

struct HttpReply {
  int status = 200;
  std::string contentType = "application/json";
  std::string body;
};

class ControlServer {
 public:
  // Binds `address` ([ADDR:]PORT; port 0 picks a free one). Throws std::runtime_error naming the
  // address when it cannot be parsed or bound (a port in use).
  ControlServer(const std::string& address, std::string token);
  ~ControlServer();  // stops serving
  ControlServer(const ControlServer&) = delete;
  ControlServer& operator=(const ControlServer&) = delete;

  const std::string& host() const;
  int port() const;
  const std::string& token() const;  // empty: none needed (loopback without --control-token)

  // Before start(): another GET route (e.g. "/" or "/api/preview.png"), behind the same token.
  // `handler` runs on a server thread and must be thread-safe.
  void addGet(const std::string& path, std::function<HttpReply()> handler);
  // Serves until stop() or destruction. The objects must outlive the server.
  void start(const Job& job, Steering& steering, StatusBoard& status);
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace app
