// libFuzzer target: the control API's request handling (apps/ControlRequests.h and the API's
// routes, apps/ControlApi.h, with the wall's window manager's, apps/WallControl.h), as the
// server runs it, without a socket. The input is a request
// as text: "METHOD PATH?A=B&C=D", header lines "Name: value", an empty line, the body. Every
// request ends in a reply, never a crash; a reply to a request without the secret is 401 or 403.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

#include "apps/ControlApi.h"
#include "apps/ControlRequests.h"
#include "apps/StatusBoard.h"
#include "apps/WallControl.h"

namespace {

constexpr const char* kToken = "0123456789abcdef0123456789abcdef";

const app::ControlRequests& requests() {
  static app::StatusBoard status;
  static app::ControlRequests* requests = [] {
    status.publish(app::RunStatus{});  // a camera to check camera requests against
    auto* r = new app::ControlRequests(app::ControlAccess{kToken, 8080, {"wall.example"}});
    r->get("/", [](const app::HttpRequest&) {
      return app::HttpReply{200, "text/html", "<p>", {}};
    });
    // Steering::submit checks the same way before queueing.
    app::addApiRoutes(
        *r, app::ControlFacts{"scivis", 64, {"left", "right"}, true},
        [](const app::SteeringRequest& request) -> std::uint64_t {
          if (const std::string problem = app::checkRequest(request); !problem.empty())
            throw std::invalid_argument(problem);
          return 1;
        },
        status);
    // The wall's routes (serve --control) on the same server: paths of their own.
    static const wall::Layout layout = [] {
      wall::Layout l;
      l.canvasWidth = 300;
      l.canvasHeight = 200;
      l.processCount = 1;
      l.displays.push_back(wall::Display{});
      l.displays.back().name = "main";
      l.displays.back().rect = {0, 0, 300, 200};
      return l;
    }();
    app::WallWindows windows;
    windows.list = [] {
      wall::service::JobDesk::Window w;
      w.number = 1;
      w.rect = {0, 0, 300, 200};
      return std::vector<wall::service::JobDesk::Window>{w};
    };
    windows.raise = [](std::uint64_t n) { return n == 1; };
    windows.close = [](std::uint64_t n, const std::string&) { return n == 1; };
    app::addWallRoutes(*r, app::WallFacts{&layout, 0xff000000u, 2}, windows);
    return r;
  }();
  return *requests;
}

std::pair<std::string_view, std::string_view> cut(std::string_view s, std::string_view at) {
  const size_t i = s.find(at);
  if (i == std::string_view::npos) return {s, {}};
  return {s.substr(0, i), s.substr(i + at.size())};
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  auto [head, body] = cut(input, "\n\n");
  auto [line, headers] = cut(head, "\n");
  auto [method, target] = cut(line, " ");
  auto [path, query] = cut(target, "?");
  app::HttpRequest request;
  request.method = method;
  request.path = path;
  request.body = body;
  while (!query.empty()) {
    auto [pair, rest] = cut(query, "&");
    auto [key, value] = cut(pair, "=");
    request.query.emplace_back(key, value);
    query = rest;
  }
  while (!headers.empty()) {
    auto [header, rest] = cut(headers, "\n");
    auto [name, value] = cut(header, ": ");
    request.headers.emplace_back(name, value);
    headers = rest;
  }
  const app::HttpReply reply = requests().handle(request);
  const std::string* auth = request.header("Authorization");
  const std::string* cookie = request.header("Cookie");
  const std::string* token = request.argument("token");
  const bool secretSent = (auth && auth->find(kToken) != std::string::npos) ||
                          (cookie && cookie->find(kToken) != std::string::npos) ||
                          (token && *token == kToken);
  if (!secretSent && reply.status != 401 && reply.status != 403) std::abort();
  return 0;
}
