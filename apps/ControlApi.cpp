#include "apps/ControlApi.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "apps/ControlRequests.h"
#include "apps/FrameDirector.h"
#include "apps/StatusBoard.h"
#include "renderers/TransferFunction.h"

namespace app {
namespace {

using Json = nlohmann::ordered_json;

// A request the API refuses: 400 with this message.
struct BadRequest : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

HttpReply json(int status, const Json& body) {
  return {status,
          "application/json",
          body.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace),
          {}};
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

// POST /api/time: {"play": bool}, {"step": n} (forward or back n steps, pausing) or {"seek": n}
// (the step to show), play with either of the others.
SteeringRequest timeRequest(const Json& j) {
  SteeringRequest r;
  r.kind = SteeringRequest::kTime;
  for (const auto& [key, value] : j.items()) {
    if (key == "play") {
      if (!value.is_boolean()) throw BadRequest("play must be true or false");
      r.play = value.get<bool>() ? 1 : 0;
      r.fields |= SteeringRequest::kPlay;
    } else if (key == "step") {
      r.stepBy = integer(value, "step");
      r.fields |= SteeringRequest::kStepBy;
    } else if (key == "seek") {
      r.seek = integer(value, "seek");
      r.fields |= SteeringRequest::kSeek;
    } else {
      throw BadRequest("unknown field '" + key + "' (time: play, step, seek)");
    }
  }
  return r;
}

// GET /api/status: what rank 0 published last, and the job's fixed facts.
Json statusJson(const StatusBoard& status, const ControlFacts& facts) {
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
         {"max_spp", facts.maxSpp},
         {"renderer", facts.renderer},
         {"last_request", {{"id", s.lastRequest}, {"frame", s.lastRequestFrame}}}};
  Json list = Json::array();
  // The swap barrier presents a frame on every display at once: one number each. A
  // display of a wall process the wall lost (--connect) shows nothing of this job.
  for (const std::string& name : s.displays.empty() ? facts.displays : s.displays) {
    const bool lost =
        std::find(s.lostDisplays.begin(), s.lostDisplays.end(), name) != s.lostDisplays.end();
    list.push_back(
        {{"name", name}, {"presented", s.presented}, {"state", lost ? "lost" : "presenting"}});
  }
  j["displays"] = list;
  if (s.timeSteps > 1)
    j["time"] = {{"step", s.view.timeStep}, {"steps", s.timeSteps}, {"playing", s.playing}};
  j["lost_displays"] = s.lostDisplays;
  j["errors"] = s.errors;
  return j;
}

}  // namespace

void addApiRoutes(ControlRequests& requests, ControlFacts facts,
                  std::function<std::uint64_t(const SteeringRequest&)> submit,
                  const StatusBoard& status) {
  requests.get("/api/status", [&status, facts](const HttpRequest&) {
    return json(200, statusJson(status, facts));
  });
  requests.post("/api/camera", [submit, &status](const HttpRequest& req) {
    SteeringRequest r = cameraRequest(parseObject(req.body));
    if (const std::string problem = checkRequest(r); !problem.empty()) throw BadRequest(problem);
    // Checked against the camera shown now (rank 0 checks again when applying); before the
    // first frame there is none to check against.
    if (!status.waitForFirstPublish(std::chrono::milliseconds(0))) {
      HttpReply reply = json(503, Json{{"error", "the wall is still starting; try again"}});
      reply.headers.emplace_back("Retry-After", "1");
      return reply;
    }
    FrameView view = status.snapshot().view;
    if (!steerView(view, view.camera, r))
      throw BadRequest("the camera would be unusable: look_at equal to position, or along up");
    return json(200, Json{{"request", submit(r)}});
  });
  requests.post("/api/settings", [submit, renderer = facts.renderer](const HttpRequest& req) {
    const SteeringRequest r = settingsRequest(parseObject(req.body), renderer);
    return json(200, Json{{"request", submit(r)}});
  });
  requests.post("/api/time", [submit, &status](const HttpRequest& req) {
    const SteeringRequest r = timeRequest(parseObject(req.body));
    if (const std::string problem = checkRequest(r); !problem.empty()) throw BadRequest(problem);
    const RunStatus now = status.snapshot();
    if (now.timeSteps <= 1) throw BadRequest("the scene has no time series");
    if (r.has(SteeringRequest::kSeek) && static_cast<std::uint32_t>(r.seek) >= now.timeSteps)
      throw BadRequest("seek " + std::to_string(r.seek) + " is past the series' " +
                       std::to_string(now.timeSteps) + " steps");
    return json(200, Json{{"request", submit(r)}});
  });
  requests.post("/api/capture", [submit, canCapture = facts.canCapture](const HttpRequest& req) {
    if (!parseObject(req.body).empty()) throw BadRequest("capture takes no fields");
    if (!canCapture) throw BadRequest("captures need a wall started with --capture DIR");
    SteeringRequest r;
    r.kind = SteeringRequest::kCapture;
    return json(200, Json{{"request", submit(r)}});
  });
  requests.post("/api/stop", [submit](const HttpRequest& req) {
    if (!parseObject(req.body).empty()) throw BadRequest("stop takes no fields");
    SteeringRequest r;
    r.kind = SteeringRequest::kStop;
    return json(200, Json{{"request", submit(r)}, {"stopping", true}});
  });
}

}  // namespace app
