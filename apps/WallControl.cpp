#include "apps/WallControl.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "apps/ControlRequests.h"
#include "wall/image/Png.h"

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

Json rectJson(const dfb::Region& r) {
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
          {"rect", rectJson(w.rect)},
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
    displays.push_back({{"name", d.name}, {"rect", rectJson(d.rect)}, {"process", d.process}});
  return {{"canvas", {{"w", facts.layout->canvasWidth}, {"h", facts.layout->canvasHeight}}},
          {"displays", std::move(displays)},
          {"background", colorText(facts.background)},
          {"max_jobs", facts.maxJobs}};
}

// The window a path's id names, if it is on the wall; else the reply that says why not.
std::optional<Window> findWindow(const std::string& id, const WallWindows& windows,
                                 HttpReply& refusal) {
  const std::optional<std::uint64_t> number = windowNumber(id);
  if (number)
    for (const Window& w : windows.list())
      if (w.number == *number) return w;
  const std::string shown = id.size() > 24 ? id.substr(0, 24) + "..." : id;
  refusal = error(404, "no window '" + shown + "' on the wall (GET /api/windows lists them)");
  return std::nullopt;
}

constexpr const char* kBodies =
    "the body must be a JSON object: {\"raise\": true}, any of {\"x\", \"y\", \"w\", \"h\"}, "
    "or {\"fullscreen\": true}";

// The rectangle a move body asks for: each of x, y, w, h given (an integer) or kept from
// `now`; {"fullscreen": true} the whole canvas. Throws std::invalid_argument naming the field.
dfb::Region askedRect(const Json& body, const dfb::Region& now, const WallFacts& facts) {
  const int canvasW = facts.layout->canvasWidth, canvasH = facts.layout->canvasHeight;
  if (body.contains("fullscreen")) {
    if (body.size() != 1)
      throw std::invalid_argument("fullscreen goes alone (it sets x, y, w and h)");
    if (!body["fullscreen"].is_boolean() || !body["fullscreen"].get<bool>())
      throw std::invalid_argument("fullscreen must be true");
    return {0, 0, canvasW, canvasH};
  }
  // Wider than int, so that x + w cannot overflow before the canvas check.
  std::int64_t v[4] = {now.x0, now.y0, now.width(), now.height()};
  const char* names[4] = {"x", "y", "w", "h"};
  for (int i = 0; i < 4; ++i) {
    if (!body.contains(names[i])) continue;
    const Json& value = body[names[i]];
    if (!value.is_number_integer() || value.get<std::int64_t>() < -(std::int64_t{1} << 31) ||
        value.get<std::int64_t>() >= (std::int64_t{1} << 31) ||
        (value.is_number_unsigned() && value.get<std::uint64_t>() >= (std::uint64_t{1} << 31)))
      throw std::invalid_argument(std::string(names[i]) +
                                  " must be an integer (canvas pixels), not " +
                                  value.dump().substr(0, 32));
    v[i] = value.get<std::int64_t>();
  }
  const std::string text = std::to_string(v[0]) + "," + std::to_string(v[1]) + "," +
                           std::to_string(v[2]) + "," + std::to_string(v[3]);
  if (v[2] <= 0 || v[3] <= 0)
    throw std::invalid_argument("window " + text + ": w and h must be positive");
  if (v[0] < 0 || v[1] < 0 || v[0] + v[2] > canvasW || v[1] + v[3] > canvasH)
    throw std::invalid_argument("window " + text + " is not inside the wall's canvas (" +
                                std::to_string(canvasW) + "x" + std::to_string(canvasH) + ")");
  return {static_cast<int>(v[0]), static_cast<int>(v[1]), static_cast<int>(v[0] + v[2]),
          static_cast<int>(v[1] + v[3])};
}

// POST /api/windows/ID: what the body asks, checked before anything is done.
HttpReply changeWindow(const HttpRequest& request, const WallFacts& facts,
                       const WallWindows& windows) {
  HttpReply refusal;
  const std::optional<Window> window = findWindow(lastSegment(request.path), windows, refusal);
  if (!window) return refusal;
  const std::string id = std::to_string(window->number);
  Json body;
  try {
    body = Json::parse(request.body);
  } catch (const Json::parse_error&) {
    throw std::invalid_argument(kBodies);
  }
  if (!body.is_object() || body.empty()) throw std::invalid_argument(kBodies);
  bool moves = false;
  for (const auto& [key, value] : body.items()) {
    if (key == "x" || key == "y" || key == "w" || key == "h" || key == "fullscreen")
      moves = true;
    else if (key != "raise")
      throw std::invalid_argument("unknown field '" + key.substr(0, 32) +
                                  "' (expected raise, or x, y, w, h, or fullscreen)");
  }
  if (moves) {
    if (body.contains("raise"))
      throw std::invalid_argument(
          "raise goes in a request of its own (a moved window keeps its place in the stack)");
    const dfb::Region rect = askedRect(body, window->rect, facts);
    int code = 200;
    const std::string why = windows.move(window->number, rect, code);
    if (code != 200) return error(code, "window " + id + ": " + why);
    return json(200, Json{{"id", id}, {"rect", rectJson(rect)}});
  }
  if (!body["raise"].is_boolean() || !body["raise"].get<bool>())
    throw std::invalid_argument("raise must be true");
  if (!windows.raise(window->number)) return error(404, "window " + id + " left the wall");
  return json(200, Json{{"id", id}, {"raised", true}});
}

HttpReply closeWindow(const HttpRequest& request, const WallWindows& windows) {
  HttpReply refusal;
  const std::optional<Window> window = findWindow(lastSegment(request.path), windows, refusal);
  if (!window) return refusal;
  const std::string id = std::to_string(window->number);
  if (!windows.close(window->number, kClosedFromThePage))
    return error(404, "window " + id + " left the wall");
  return json(200, Json{{"id", id}, {"closed", true}});
}

// GET /api/windows/ID/thumbnail: the window's last thumbnail as PNG (lossless: what the
// displays show, shrunk; transparent where only bezels are).
HttpReply thumbnail(const HttpRequest& request, const WallFacts& facts,
                    const WallWindows& windows) {
  HttpReply refusal;
  const std::optional<Window> window =
      findWindow(segmentBeforeLast(request.path), windows, refusal);
  if (!window) return refusal;
  if (facts.maxJobs < 2)
    return error(503, "the wall makes thumbnails with serve --max-jobs 2 or more only");
  if (!window->thumbnail)
    return error(503, "window " + std::to_string(window->number) +
                          " has no thumbnail yet (the wall makes one about every second once "
                          "its job shows frames)");
  return {200, "image/png", wall::encodePng(*window->thumbnail), {}};
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
  requests.get("/api/windows/*/thumbnail", [facts, windows](const HttpRequest& request) {
    return thumbnail(request, facts, windows);
  });
  requests.post("/api/windows/*", [facts, windows](const HttpRequest& request) {
    return changeWindow(request, facts, windows);
  });
  requests.remove("/api/windows/*",
                  [windows](const HttpRequest& request) { return closeWindow(request, windows); });
}

}  // namespace app
