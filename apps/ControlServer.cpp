#include "apps/ControlServer.h"

#include <algorithm>

#include <httplib.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <thread>
#include <vector>

#include "apps/FrameDirector.h"
#include "apps/Job.h"
#include "apps/StatusBoard.h"
#include "apps/Steering.h"
#include "renderers/TransferFunction.h"

namespace app {
namespace {

using Json = nlohmann::ordered_json;

// A request the API refuses: 400 with this message.
struct BadRequest : std::runtime_error {
  using std::runtime_error::runtime_error;
};

HttpReply json(int status, const Json& body) { return {status, "application/json", body.dump()}; }
HttpReply error(int status, const std::string& message) {
  return json(status, Json{{"error", message}});
}

bool isLoopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

// 32 hex digits from the kernel's random pool.
std::string generateToken() {
  std::ifstream random("/dev/urandom", std::ios::binary);
  unsigned char bytes[16];
  if (!random.read(reinterpret_cast<char*>(bytes), sizeof bytes))
    throw std::runtime_error("--control: cannot read /dev/urandom for a token");
  static const char* hex = "0123456789abcdef";
  std::string token;
  for (unsigned char b : bytes) token += {hex[b >> 4], hex[b & 15]};
  return token;
}

// Compares in time independent of where they differ: the token is a secret.
bool sameSecret(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

Json vec3(const renderers::Vec3& v) { return Json::array({v.x, v.y, v.z}); }

double finiteNumber(const Json& v, const std::string& field) {
  if (!v.is_number()) throw BadRequest(field + " must be a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) throw BadRequest(field + " must be a finite number");
  return d;
}

float boundedNumber(const Json& v, const std::string& field) {
  const double d = finiteNumber(v, field);
  if (std::abs(d) > 1e30) throw BadRequest(field + " is out of range");
  return static_cast<float>(d);
}

std::int32_t integer(const Json& v, const std::string& field) {
  if (!v.is_number_integer()) throw BadRequest(field + " must be an integer");
  const std::int64_t i = v.get<std::int64_t>();
  if (i < -(1ll << 30) || i > (1ll << 30)) throw BadRequest(field + " is out of range");
  return static_cast<std::int32_t>(i);
}

renderers::Vec3 vector3(const Json& v, const std::string& field) {
  if (!v.is_array() || v.size() != 3) throw BadRequest(field + " must be an array of 3 numbers");
  return {boundedNumber(v[0], field), boundedNumber(v[1], field), boundedNumber(v[2], field)};
}

// An empty body is {}: `curl -X POST URL` sends none, and the first thing people type should work.
Json parseObject(const std::string& body) {
  if (body.empty()) return Json::object();
  Json j = Json::parse(body, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) throw BadRequest("the body is not valid JSON");
  if (!j.is_object()) throw BadRequest("the body must be a JSON object");
  return j;
}

SteeringRequest cameraRequest(const Json& j) {
  using R = SteeringRequest;
  R r;
  r.kind = R::kCamera;
  for (const auto& [key, value] : j.items()) {
    if (key == "position") {
      r.position = vector3(value, key), r.fields |= R::kPosition;
    } else if (key == "look_at") {
      r.lookAt = vector3(value, key), r.fields |= R::kLookAt;
    } else if (key == "up") {
      r.up = vector3(value, key), r.fields |= R::kUp;
    } else if (key == "fov") {
      r.fov = boundedNumber(value, key), r.fields |= R::kFov;
    } else if (key == "orbit") {
      r.orbit = boundedNumber(value, key), r.fields |= R::kOrbit;
    } else if (key == "pan") {
      if (!value.is_array() || value.size() != 2)
        throw BadRequest("pan must be an array of 2 numbers [dx, dy]");
      r.pan[0] = boundedNumber(value[0], key);
      r.pan[1] = boundedNumber(value[1], key);
      r.fields |= R::kPan;
    } else if (key == "dolly") {
      r.dolly = boundedNumber(value, key), r.fields |= R::kDolly;
    } else {
      throw BadRequest("unknown field '" + key +
                       "' (camera fields: position, look_at, up, fov, orbit, pan, dolly)");
    }
  }
  return r;
}

SteeringRequest settingsRequest(const Json& j, const std::string& renderer) {
  using R = SteeringRequest;
  R r;
  r.kind = R::kSettings;
  for (const auto& [key, value] : j.items()) {
    if (key == "exposure") {
      r.exposure = boundedNumber(value, key), r.fields |= R::kExposure;
    } else if (key == "spp") {
      r.spp = integer(value, key), r.fields |= R::kSpp;
    } else if (key == "max_depth") {
      if (renderer != "pathtracer") throw BadRequest("max_depth is a setting of the pathtracer");
      r.maxDepth = integer(value, key), r.fields |= R::kMaxDepth;
    } else if (key == "transfer_function") {
      if (renderer != "scivis") throw BadRequest("transfer_function is a setting of scivis");
      if (!value.is_string()) throw BadRequest("transfer_function must be a preset name");
      const std::vector<std::string> names = renderers::transferFunctionPresetNames();
      r.transferFunction = -1;
      std::string known;
      for (size_t i = 0; i < names.size(); ++i) {
        if (names[i] == value.get<std::string>()) r.transferFunction = static_cast<int>(i);
        known += (i ? ", " : "") + names[i];
      }
      if (r.transferFunction < 0)
        throw BadRequest("unknown transfer_function preset (choose " + known + ")");
      r.fields |= R::kTransferFunction;
    } else if (key == "opacity_scale") {
      if (renderer != "scivis") throw BadRequest("opacity_scale is a setting of scivis");
      r.opacityScale = boundedNumber(value, key), r.fields |= R::kOpacityScale;
    } else {
      throw BadRequest("unknown field '" + key +
                       "' (settings: exposure, spp, max_depth, transfer_function, opacity_scale)");
    }
  }
  return r;
}

}  // namespace

struct ControlServer::Impl {
  httplib::Server server;
  std::string host, token;
  int port = 0;
  std::thread thread;
  std::vector<std::pair<std::string, std::function<HttpReply()>>> extraGets;
  std::map<std::string, httplib::Server::Handler> posts;  // by path, for bodiless POSTs

  bool authorized(const httplib::Request& req) const {
    if (token.empty()) return true;
    const std::string auth = req.get_header_value("Authorization");
    if (auth.rfind("Bearer ", 0) == 0 && sameSecret(auth.substr(7), token)) return true;
    return req.has_param("token") && sameSecret(req.get_param_value("token"), token);
  }
};

ControlServer::ControlServer(const std::string& address, std::string token)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const size_t colon = address.rfind(':');
  m.host = colon == std::string::npos ? "127.0.0.1" : address.substr(0, colon);
  const std::string port = colon == std::string::npos ? address : address.substr(colon + 1);
  if (m.host.size() > 2 && m.host.front() == '[' && m.host.back() == ']')
    m.host = m.host.substr(1, m.host.size() - 2);
  int value = -1;
  const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (ec != std::errc() || end != port.data() + port.size() || value < 0 || value > 65535 ||
      m.host.empty())
    throw std::runtime_error("--control " + address +
                             ": expected [ADDR:]PORT with a port in 0..65535, e.g. 8080 or "
                             "0.0.0.0:8080");
  m.token = std::move(token);
  if (m.token.empty() && !isLoopback(m.host)) m.token = generateToken();
  m.server.new_task_queue = [] { return new httplib::ThreadPool(2); };
  m.server.set_payload_max_length(64 * 1024);
  // The pool joins its threads on stop; an idle keep-alive connection holds one this long.
  m.server.set_keep_alive_timeout(1);
  if (value == 0) {
    m.port = m.server.bind_to_any_port(m.host);
  } else if (m.server.bind_to_port(m.host, value)) {
    m.port = value;
  }
  if (m.port <= 0)
    throw std::runtime_error("--control " + address + ": cannot listen on " + m.host + " port " +
                             port + " (in use, or not an address of this host)");
}

ControlServer::~ControlServer() { stop(); }

const std::string& ControlServer::host() const { return impl_->host; }
int ControlServer::port() const { return impl_->port; }
const std::string& ControlServer::token() const { return impl_->token; }

void ControlServer::addGet(const std::string& path, std::function<HttpReply()> handler) {
  impl_->extraGets.emplace_back(path, std::move(handler));
}

void ControlServer::start(const Job& job, Steering& steering, StatusBoard& status) {
  Impl& m = *impl_;
  auto reply = [](httplib::Response& res, const HttpReply& r) {
    res.status = r.status;
    res.set_content(r.body, r.contentType.c_str());
  };
  // Every route: the token first, then the handler; a BadRequest is a 400, anything else a 500.
  auto guarded = [&m, reply](std::function<HttpReply(const httplib::Request&)> handler) {
    return [&m, reply, handler](const httplib::Request& req, httplib::Response& res) {
      if (!m.authorized(req)) {
        res.set_header("WWW-Authenticate", "Bearer");
        return reply(res, error(401, "a valid token is required (Authorization: Bearer TOKEN)"));
      }
      try {
        reply(res, handler(req));
      } catch (const BadRequest& e) {
        reply(res, error(400, e.what()));
      } catch (const std::invalid_argument& e) {  // Steering::submit's range checks
        reply(res, error(400, e.what()));
      } catch (const std::exception& e) {
        reply(res, error(500, e.what()));
      }
    };
  };
  const std::string renderer = job.options.renderer;
  std::vector<std::string> displays;
  if (job.layout)
    for (const auto& d : job.layout->displays) displays.push_back(d.name);

  m.server.Get(
      "/api/status", guarded([&status, renderer, displays, &job](const auto&) {
        const RunStatus s = status.snapshot();
        Json j{{"frame", s.frame},
               {"fps", s.fps},
               {"spp", s.spp},
               {"epoch", s.epoch},
               {"idle", s.idle},
               {"presented", s.presented},
               {"camera",
                {{"position", vec3(s.view.camera.position)},
                 {"look_at", vec3(s.view.camera.lookAt)},
                 {"up", vec3(s.view.camera.up)},
                 {"fov", s.view.camera.fovY}}},
               {"settings",
                {{"exposure", s.view.exposure},
                 {"spp", s.view.spp},
                 {"max_depth", s.view.maxDepth},
                 {"transfer_function", s.view.transferFunction < 0
                                           ? Json("scene")
                                           : Json(renderers::transferFunctionPresetNames().at(
                                                 static_cast<size_t>(s.view.transferFunction)))},
                 {"opacity_scale", s.view.opacityScale}}},
               {"max_spp", job.options.maxSpp},
               {"renderer", renderer},
               {"last_request", {{"id", s.lastRequest}, {"frame", s.lastRequestFrame}}}};
        Json list = Json::array();
        // The swap barrier presents a frame on every display at once: one number each. A
        // display of a wall process the wall lost (--connect) shows nothing of this job.
        for (const std::string& name : displays) {
          const bool lost =
              std::find(s.lostDisplays.begin(), s.lostDisplays.end(), name) != s.lostDisplays.end();
          list.push_back({{"name", name},
                          {"presented", s.presented},
                          {"state", lost ? "lost" : "presenting"}});
        }
        j["displays"] = list;
        j["lost_displays"] = s.lostDisplays;
        j["errors"] = s.errors;
        return json(200, j);
      }));
  // Every POST route is kept by path too: the pre-routing handler below serves a POST without a
  // body itself.
  const auto post = [&m](const std::string& path, httplib::Server::Handler handler) {
    m.posts[path] = handler;
    m.server.Post(path, std::move(handler));
  };
  post("/api/camera", guarded([&steering, &status](const httplib::Request& req) {
         SteeringRequest r = cameraRequest(parseObject(req.body));
         if (const std::string problem = checkRequest(r); !problem.empty())
           throw BadRequest(problem);
         // Checked against the camera shown now (rank 0 checks again when applying).
         if (!status.waitForFirstPublish(std::chrono::seconds(30)))
           return json(503, Json{{"error", "the wall is still starting; try again"}});
         FrameView view = status.snapshot().view;
         if (!steerView(view, view.camera, r))
           throw BadRequest("the camera would be unusable: look_at equal to position, or along up");
         return json(200, Json{{"request", steering.submit(r)}});
       }));
  post("/api/settings", guarded([&steering, renderer](const httplib::Request& req) {
         const SteeringRequest r = settingsRequest(parseObject(req.body), renderer);
         return json(200, Json{{"request", steering.submit(r)}});
       }));
  const bool canCapture = job.layout && !job.options.captureDir.empty();
  post("/api/capture", guarded([&steering, canCapture](const httplib::Request& req) {
         if (!parseObject(req.body).empty()) throw BadRequest("capture takes no fields");
         if (!canCapture) throw BadRequest("captures need a wall started with --capture DIR");
         SteeringRequest r;
         r.kind = SteeringRequest::kCapture;
         return json(200, Json{{"request", steering.submit(r)}});
       }));
  post("/api/stop", guarded([&steering](const httplib::Request& req) {
         if (!parseObject(req.body).empty()) throw BadRequest("stop takes no fields");
         SteeringRequest r;
         r.kind = SteeringRequest::kStop;
         return json(200, Json{{"request", steering.submit(r)}, {"stopping", true}});
       }));
  for (const auto& [path, handler] : m.extraGets)
    m.server.Get(path, guarded([handler](const auto&) { return handler(); }));
  // A POST with neither Content-Length nor Transfer-Encoding has an empty body (RFC 9112, 6.3),
  // and `curl -X POST URL` sends just that. httplib 0.11 instead reads such a body until the
  // connection closes (Server::routing -> read_content -> detail::read_content_without_length),
  // which a client waiting for its answer never does: 400 after the 5 s read timeout. The
  // pre-routing handler runs before that read, so it serves these requests itself, with the
  // empty body (the handlers take it as {}); the connection stays usable for the next request.
  m.server.set_pre_routing_handler(
      [&m, reply](const httplib::Request& req, httplib::Response& res) {
        if (req.method != "POST" || req.has_header("Content-Length") ||
            req.has_header("Transfer-Encoding"))
          return httplib::Server::HandlerResponse::Unhandled;
        const auto found = m.posts.find(req.path);
        if (found == m.posts.end())
          reply(res, error(404, "no such endpoint (see README, \"Steering the wall\")"));
        else
          found->second(req, res);
        return httplib::Server::HandlerResponse::Handled;
      });
  // httplib's own refusals come with no body: say what went wrong.
  m.server.set_error_handler([reply](const httplib::Request& req, httplib::Response& res) {
    if (!res.body.empty()) return;
    if (res.status == 404)
      reply(res, error(404, "no such endpoint (see README, \"Steering the wall\")"));
    else if (res.status == 400 && req.method == "POST")
      reply(res, error(400,
                       "the request's body could not be read: it must be as long as its "
                       "Content-Length says, or validly chunked"));
    else
      reply(res, error(res.status, "request refused"));
  });
  m.thread = std::thread([&m] { m.server.listen_after_bind(); });
}

void ControlServer::stop() {
  Impl& m = *impl_;
  if (m.thread.joinable()) {
    // stop() does nothing before the listening loop runs (httplib): let it start first.
    for (int i = 0; i < 500 && !m.server.is_running(); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    m.server.stop();
    m.thread.join();
  }
}

}  // namespace app
