#include "apps/WallControl.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "apps/ControlRequests.h"

namespace app {
namespace {

using Json = nlohmann::ordered_json;
using Window = wall::service::JobDesk::Window;
using State = wall::service::JobDesk::State;

// Names and hosts come from jobs: bytes that are not UTF-8 are replaced, not thrown.
HttpReply json(int status, const Json& body) {
  return {
      status, "application/json", body.dump(-1, ' ', false, Json::error_handler_t::replace), {}};
}

HttpReply error(int status, const std::string& message) {
  return json(status, Json{{"error", message}});
}

Json rect(const dfb::Region& r) {
  return {{"x", r.x0}, {"y", r.y0}, {"w", r.width()}, {"h", r.height()}};
}

std::string stateName(const Window& w) {
  switch (w.state) {
    case State::Starting:
      return "starting";
    case State::Running:
      return w.idle ? "idle" : "running";
    default:
      return "ending";
  }
}

Json windowJson(const Window& w) {
  return {{"id", std::to_string(w.number)},
          {"job", w.job},
          {"host", w.host},
          {"rect", rect(w.rect)},
          {"z", w.z},
          {"fps", std::round(w.fps * 10) / 10},
          {"state", stateName(w)},
          {"frames", w.frames},
          {"page", w.page.empty() ? Json() : Json(w.page)}};
}

std::string colorText(std::uint32_t rgba) {
  char text[8];
  std::snprintf(text, sizeof text, "#%02x%02x%02x", rgba & 0xffu, (rgba >> 8) & 0xffu,
                (rgba >> 16) & 0xffu);
  return text;
}

Json wallJson(const WallFacts& facts) {
  Json displays = Json::array();
  for (const wall::Display& d : facts.layout->displays)
    displays.push_back({{"name", d.name}, {"rect", rect(d.rect)}, {"process", d.process}});
  return {{"canvas", {{"w", facts.layout->canvasWidth}, {"h", facts.layout->canvasHeight}}},
          {"displays", std::move(displays)},
          {"background", colorText(facts.background)},
          {"max_jobs", facts.maxJobs}};
}

// The window a path's id names, if it is on the wall; else the reply that says why not.
std::optional<std::uint64_t> findWindow(const HttpRequest& request, const WallWindows& windows,
                                        HttpReply& refusal) {
  const std::string id = lastSegment(request.path);
  const std::optional<std::uint64_t> number = windowNumber(id);
  if (number)
    for (const Window& w : windows.list())
      if (w.number == *number) return number;
  const std::string shown = id.size() > 24 ? id.substr(0, 24) + "..." : id;
  refusal = error(404, "no window '" + shown + "' on the wall (GET /api/windows lists them)");
  return std::nullopt;
}

// POST /api/windows/ID: what the body asks, checked before anything is done.
HttpReply changeWindow(const HttpRequest& request, const WallWindows& windows) {
  HttpReply refusal;
  const std::optional<std::uint64_t> number = findWindow(request, windows, refusal);
  if (!number) return refusal;
  Json body;
  try {
    body = Json::parse(request.body);
  } catch (const Json::parse_error&) {
    throw std::invalid_argument(
        "the body must be a JSON object: {\"raise\": true}, or {\"x\", \"y\", \"w\", \"h\"}");
  }
  if (!body.is_object() || body.empty())
    throw std::invalid_argument(
        "the body must be a JSON object: {\"raise\": true}, or {\"x\", \"y\", \"w\", \"h\"}");
  bool moves = false;
  for (const auto& [key, value] : body.items()) {
    if (key == "x" || key == "y" || key == "w" || key == "h" || key == "fullscreen")
      moves = true;
    else if (key != "raise")
      throw std::invalid_argument("unknown field '" + key.substr(0, 32) +
                                  "' (expected raise, or x, y, w, h, or fullscreen)");
  }
  if (moves)
    return error(501,
                 "moving and resizing a window is not done yet: its job keeps its place and size "
                 "(raise and close work)");
  if (!body["raise"].is_boolean() || !body["raise"].get<bool>())
    throw std::invalid_argument("raise must be true");
  if (!windows.raise(*number))
    return error(404, "window " + std::to_string(*number) + " left the wall");
  return json(200, Json{{"id", std::to_string(*number)}, {"raised", true}});
}

HttpReply closeWindow(const HttpRequest& request, const WallWindows& windows) {
  HttpReply refusal;
  const std::optional<std::uint64_t> number = findWindow(request, windows, refusal);
  if (!number) return refusal;
  if (!windows.close(*number, kClosedFromThePage))
    return error(404, "window " + std::to_string(*number) + " left the wall");
  return json(200, Json{{"id", std::to_string(*number)}, {"closed", true}});
}

}  // namespace

std::optional<std::uint64_t> windowNumber(const std::string& id) {
  if (id.empty() || id.size() > 20 || id[0] == '0') return std::nullopt;
  std::uint64_t number = 0;
  const auto [end, ec] = std::from_chars(id.data(), id.data() + id.size(), number);
  if (ec != std::errc() || end != id.data() + id.size()) return std::nullopt;
  return number;
}

void addWallRoutes(ControlRequests& requests, WallFacts facts, WallWindows windows) {
  requests.get("/api/wall",
               [body = wallJson(facts)](const HttpRequest&) { return json(200, body); });
  requests.get("/api/windows", [windows](const HttpRequest&) {
    Json list = Json::array();
    for (const Window& w : windows.list()) list.push_back(windowJson(w));
    return json(200, list);
  });
  requests.post("/api/windows/*",
                [windows](const HttpRequest& request) { return changeWindow(request, windows); });
  requests.remove("/api/windows/*",
                  [windows](const HttpRequest& request) { return closeWindow(request, windows); });
}

}  // namespace app
