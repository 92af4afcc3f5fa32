#pragma once
// What the control server answers, decided without a socket: one request in, one reply out, so
// that the whole decision (who may ask, what is asked) is tested and fuzzed as it runs
// (tests/fuzz/FuzzControlRequests.cpp). apps/ControlServer.h carries requests to it.
//
// Every request passes, in order:
//   1. Host: the bound address, a loopback name (any port: an SSH tunnel's local port), this
//      host's names and addresses when bound to all interfaces, or a --control-host NAME; else
//      403 (a DNS-rebinding page reaches 127.0.0.1 under its own name).
//   2. The secret: `Authorization: Bearer TOKEN` (scripts, curl), or the page's cookie, which
//      GET /?token=TOKEN sets before redirecting to / (the token leaves the address bar and no
//      later URL carries it); else 401.
//   3. A POST authenticated by the cookie must be `Content-Type: application/json` from the
//      server's own Origin; else 403 (another page's forms and no-cors fetches send neither).
// Every reply carries a Content-Security-Policy, X-Frame-Options DENY, nosniff, no-store and
// no-referrer.
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace app {

struct HttpRequest {
  std::string method;                                        // "GET", "POST", ...
  std::string path;                                          // without the query
  std::vector<std::pair<std::string, std::string>> query;    // decoded arguments, in order
  std::vector<std::pair<std::string, std::string>> headers;  // as sent
  std::string body;

  // The first header or query argument of that name (headers: any case), or nullptr.
  const std::string* header(std::string_view name) const;
  const std::string* argument(std::string_view name) const;
};

struct HttpReply {
  int status = 200;
  std::string contentType = "application/json";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;  // besides the security headers
};

// Who may ask.
struct ControlAccess {
  std::string token;               // never empty
  int port = 0;                    // the server's port (in Host and Origin)
  std::vector<std::string> hosts;  // names and addresses a Host header may carry with the port
};

class ControlRequests {
 public:
  using Handler = std::function<HttpReply(const HttpRequest&)>;

  explicit ControlRequests(ControlAccess access);

  // Before the first handle(). A handler that throws std::invalid_argument gives 400 with its
  // message, any other exception 500. A path ending in "/*" serves every path one segment
  // deeper (its handler reads the segment from the request's path: see lastSegment), and one
  // ending in "/*/LEAF" every path with one segment in its place (see segmentBeforeLast).
  void get(const std::string& path, Handler handler);
  void post(const std::string& path, Handler handler);
  void remove(const std::string& path, Handler handler);  // DELETE

  // Thread-safe once the routes are set.
  HttpReply handle(const HttpRequest& request) const;

  // The cookie the page authenticates with (its name carries the port: cookies of two servers
  // on one host would clash otherwise).
  const std::string& cookieName() const { return cookieName_; }

 private:
  std::optional<HttpReply> hostRefusal(const HttpRequest& request) const;
  std::optional<HttpReply> authRefusal(const HttpRequest& request) const;
  HttpReply route(const HttpRequest& request) const;
  // The handler of `method` for `path` (exact, else its "/*" pattern), or nullptr.
  const Handler* find(const std::string& method, const std::string& path) const;

  ControlAccess access_;
  std::string cookieName_;
  std::map<std::string, std::map<std::string, Handler>> routes_;  // method -> path -> handler
};

// What follows the last '/' of a path served by a "/*" route ("/api/windows/3": "3").
std::string lastSegment(const std::string& path);
// The segment before the last of a path served by a "/*/LEAF" route ("/api/windows/3/thumbnail":
// "3").
std::string segmentBeforeLast(const std::string& path);

// Bodies larger than this are refused with 413 before they are read to the end.
constexpr std::size_t kMaxControlBody = 64 * 1024;

}  // namespace app
