#include "apps/ControlRequests.h"

#include <arpa/inet.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "apps/ControlSecret.h"

namespace app {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// Messages may quote what a client sent, in any bytes: invalid UTF-8 is replaced, not thrown.
HttpReply error(int status, const std::string& message) {
  return {status,
          "application/json",
          nlohmann::json{{"error", message}}.dump(-1, ' ', false,
                                                  nlohmann::json::error_handler_t::replace),
          {}};
}

// What a client sent, quoted in a message: short.
std::string quoted(const std::string& sent) {
  return "'" + (sent.size() > 64 ? sent.substr(0, 64) + "..." : sent) + "'";
}

// A Host header's name (lower case, IPv6 without brackets) and port (-1 when absent); false when
// it is not of that form.
bool splitHost(std::string_view host, std::string& name, int& port) {
  port = -1;
  std::string_view portText;
  if (!host.empty() && host.front() == '[') {
    const size_t close = host.find(']');
    if (close == std::string_view::npos) return false;
    name = lower(host.substr(1, close - 1));
    const std::string_view rest = host.substr(close + 1);
    if (!rest.empty()) {
      if (rest.front() != ':') return false;
      portText = rest.substr(1);
    }
  } else {
    const size_t colon = host.rfind(':');
    name = lower(host.substr(0, colon));
    if (colon != std::string_view::npos) portText = host.substr(colon + 1);
    if (name.find(':') != std::string::npos) return false;
  }
  if (name.empty()) return false;
  if (host.back() == ':') return false;
  if (!portText.empty()) {
    const auto [end, ec] =
        std::from_chars(portText.data(), portText.data() + portText.size(), port);
    if (ec != std::errc() || end != portText.data() + portText.size() || port < 1 || port > 65535)
      return false;
  }
  return true;
}

// Names a browser reaches only on this host: no page can rebind them to itself.
bool isLoopbackName(const std::string& name) {
  if (name == "localhost" || name == "::1") return true;
  in_addr v4{};
  return inet_pton(AF_INET, name.c_str(), &v4) == 1 && (ntohl(v4.s_addr) >> 24) == 127;
}

// The value of cookie `name` in a Cookie header, or empty.
std::string cookieValue(const std::string& header, const std::string& name) {
  std::string_view rest = header;
  while (!rest.empty()) {
    const size_t semicolon = rest.find(';');
    const std::string_view pair = trim(rest.substr(0, semicolon));
    rest = semicolon == std::string_view::npos ? std::string_view() : rest.substr(semicolon + 1);
    const size_t equals = pair.find('=');
    if (equals != std::string_view::npos && pair.substr(0, equals) == name)
      return std::string(pair.substr(equals + 1));
  }
  return {};
}

void addSecurityHeaders(HttpReply& reply) {
  // The page needs nothing but its own files: no inline script or style, no frame, no form.
  reply.headers.emplace_back("Content-Security-Policy",
                             "default-src 'self'; object-src 'none'; base-uri 'none'; "
                             "form-action 'none'; frame-ancestors 'none'");
  reply.headers.emplace_back("X-Frame-Options", "DENY");
  reply.headers.emplace_back("X-Content-Type-Options", "nosniff");
  reply.headers.emplace_back("Cache-Control", "no-store");
  reply.headers.emplace_back("Referrer-Policy", "no-referrer");
  // Another page of this host (same site, so the cookie goes along) may not embed the preview.
  reply.headers.emplace_back("Cross-Origin-Resource-Policy", "same-origin");
}

}  // namespace

const std::string* HttpRequest::header(std::string_view name) const {
  const std::string wanted = lower(name);
  for (const auto& [key, value] : headers)
    if (lower(key) == wanted) return &value;
  return nullptr;
}

const std::string* HttpRequest::argument(std::string_view name) const {
  for (const auto& [key, value] : query)
    if (key == name) return &value;
  return nullptr;
}

ControlRequests::ControlRequests(ControlAccess access)
    : access_(std::move(access)), cookieName_("dfbwall-control-" + std::to_string(access_.port)) {
  if (access_.token.empty()) throw std::logic_error("ControlRequests: the token must be set");
  for (std::string& host : access_.hosts) host = lower(host);
}

void ControlRequests::get(const std::string& path, Handler handler) {
  routes_["GET"][path] = std::move(handler);
}

void ControlRequests::post(const std::string& path, Handler handler) {
  routes_["POST"][path] = std::move(handler);
}

void ControlRequests::remove(const std::string& path, Handler handler) {
  routes_["DELETE"][path] = std::move(handler);
}

std::string lastSegment(const std::string& path) { return path.substr(path.rfind('/') + 1); }

std::string segmentBeforeLast(const std::string& path) {
  const size_t slash = path.rfind('/');
  if (slash == std::string::npos || slash == 0) return {};
  const size_t before = path.rfind('/', slash - 1);
  return path.substr(before + 1, slash - before - 1);
}

const ControlRequests::Handler* ControlRequests::find(const std::string& method,
                                                      const std::string& path) const {
  const auto routes = routes_.find(method == "HEAD" ? "GET" : method);
  if (routes == routes_.end()) return nullptr;
  if (const auto exact = routes->second.find(path); exact != routes->second.end())
    return &exact->second;
  // One segment below a "/*" route: not empty, no further '/'.
  const size_t slash = path.rfind('/');
  if (slash == std::string::npos || slash + 1 == path.size()) return nullptr;
  const auto pattern = routes->second.find(path.substr(0, slash + 1) + "*");
  if (pattern != routes->second.end()) return &pattern->second;
  // A "/*/LEAF" route: the segment before the last one, not empty.
  const size_t before = slash == 0 ? std::string::npos : path.rfind('/', slash - 1);
  if (before == std::string::npos || before + 1 == slash) return nullptr;
  const auto inner = routes->second.find(path.substr(0, before + 1) + "*" + path.substr(slash));
  return inner == routes->second.end() ? nullptr : &inner->second;
}

// 403 with why the request's Host is not this server, or nullopt.
std::optional<HttpReply> ControlRequests::hostRefusal(const HttpRequest& request) const {
  const std::string* host = request.header("Host");
  std::string name;
  int port = -1;
  if (!host || !splitHost(*host, name, port))
    return error(403, "a Host header (NAME:PORT) is required");
  const bool known =
      std::find(access_.hosts.begin(), access_.hosts.end(), name) != access_.hosts.end();
  const bool ourPort = port == access_.port || (port < 0 && access_.port == 80);
  if (isLoopbackName(name) || (known && ourPort)) return std::nullopt;
  return error(403, "Host " + quoted(*host) +
                        " is not an address of this server (give the name with --control-host "
                        "NAME)");
}

// 401 or 403 with why the request may not go on, or nullopt.
std::optional<HttpReply> ControlRequests::authRefusal(const HttpRequest& request) const {
  if (const std::string* auth = request.header("Authorization")) {
    const std::string_view value = trim(*auth);
    if (value.size() > 7 && lower(value.substr(0, 7)) == "bearer " &&
        sameSecret(std::string(trim(value.substr(7))), access_.token))
      return std::nullopt;
    return error(401,
                 "the Authorization header does not carry the token (Authorization: Bearer "
                 "TOKEN)");
  }
  const std::string* cookies = request.header("Cookie");
  if (!cookies || !sameSecret(cookieValue(*cookies, cookieName_), access_.token))
    return error(401,
                 "the token is required: open the page at the address dfbwall printed (ending in "
                 "/?token=TOKEN), or send Authorization: Bearer TOKEN");
  if (request.method == "GET" || request.method == "HEAD") return std::nullopt;
  // The cookie goes along with requests other pages of this site make: a change must come from
  // our own page, which sends JSON (another origin cannot without a preflight we never answer).
  const std::string* type = request.header("Content-Type");
  const std::string media =
      type ? lower(trim(std::string_view(*type).substr(0, type->find(';')))) : std::string();
  if (media != "application/json")
    return error(403, "a change from the page must be sent as Content-Type: application/json");
  const std::string* origin = request.header("Origin");
  const std::string* host = request.header("Host");
  if (!origin || lower(trim(*origin)) != "http://" + lower(trim(*host)))
    return error(403,
                 "a change from a page must come from this server's own page (its Origin is "
                 "http:// and its Host)");
  return std::nullopt;
}

HttpReply ControlRequests::handle(const HttpRequest& request) const {
  const bool pageAddress = request.path == "/" || request.path == "/index.html";
  std::optional<HttpReply> refused = hostRefusal(request);
  HttpReply reply;
  if (refused) {
    reply = std::move(*refused);
  } else if (pageAddress && request.method == "GET" && request.argument("token")) {
    // The address dfbwall printed: swap the token for the cookie, and send the browser to the
    // page without it (the address bar and the history lose it).
    if (sameSecret(*request.argument("token"), access_.token)) {
      reply = HttpReply{303, "text/plain", "the page is at /\n", {}};
      reply.headers.emplace_back("Location", "/");
      reply.headers.emplace_back(
          "Set-Cookie", cookieName_ + "=" + access_.token + "; Path=/; HttpOnly; SameSite=Strict");
    } else {
      reply = error(401, "the token in this address is not the server's");
    }
  } else if ((refused = authRefusal(request))) {
    reply = std::move(*refused);
    if (reply.status == 401) reply.headers.emplace_back("WWW-Authenticate", "Bearer");
  } else {
    reply = route(request);
  }
  addSecurityHeaders(reply);
  return reply;
}

HttpReply ControlRequests::route(const HttpRequest& request) const {
  const Handler* found = find(request.method, request.path);
  if (!found) {
    std::string allowed;
    for (const auto& [method, routes] : routes_)
      if (find(method, request.path)) allowed += (allowed.empty() ? "" : ", ") + method;
    HttpReply reply =
        !allowed.empty()
            ? error(405, quoted(request.method) + " is not served at " + quoted(request.path))
            : error(404,
                    "no such endpoint (see docs/service.md, \"Steering "
                    "the wall\")");
    if (!allowed.empty()) reply.headers.emplace_back("Allow", allowed);
    return reply;
  }
  if (request.body.size() > kMaxControlBody)
    return error(413, "the body is larger than " + std::to_string(kMaxControlBody) + " bytes");
  try {
    return (*found)(request);
  } catch (const std::invalid_argument& e) {
    return error(400, e.what());
  } catch (const std::exception& e) {
    return error(500, e.what());
  }
}

}  // namespace app
