#include "apps/CameraPath.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "base/TomlDiagnostics.h"
#include "renderers/TomlReader.h"

namespace app {

namespace {

// One [[keyframe]]: up and fov carry over from `previous` (the scene's camera for the first).
void readKeyframe(renderers::TomlReader& r, const toml::table& t, int number,
                  const renderers::CameraDesc& previous, double earlier, bool first,
                  renderers::CameraDesc& camera, double& time) {
  const std::string what = "keyframe #" + std::to_string(number);
  r.onlyKeys(t, what, {"time", "position", "look_at", "up", "fov", "step"});
  const std::size_t before = r.problems();
  const toml::node* timeNode = r.need(t, "time", what);
  time = r.number(timeNode, what + ".time");
  if (r.problems() == before && time < 0)
    r.problem(*timeNode, what + ".time", "must not be negative");
  else if (r.problems() == before && !first && time <= earlier)
    r.problem(
        *timeNode, what + ".time",
        "must be later than the keyframe before (" + renderers::TomlReader::text(earlier) + ")");
  camera = previous;
  camera.position = r.vec3(r.need(t, "position", what), what + ".position");
  camera.lookAt = r.vec3(r.need(t, "look_at", what), what + ".look_at");
  camera.up = r.vec3(t, "up", what, previous.up);
  camera.fovY = r.number(t, "fov", what, previous.fovY);
  // (A fov carried over from the scene's camera may be out of range too: reported here.)
  if (!(camera.fovY >= 1 && camera.fovY <= 170))
    r.problem(t.get("fov") ? *t.get("fov") : t, what + ".fov",
              "must be in [1, 170] degrees, not " + renderers::TomlReader::text(camera.fovY));
  r.settle();
  const renderers::Vec3 view = camera.lookAt - camera.position;
  if (renderers::length(view) <= 0 || renderers::length(renderers::cross(view, camera.up)) <= 0)
    r.fail(t, what, "look_at must differ from position and not lie along up");
}

}  // namespace

CameraPath CameraPath::load(const std::string& path, const renderers::CameraDesc& sceneCamera,
                            std::uint32_t timeSteps) {
  base::TomlDiagnostics diagnostics(path);
  std::optional<toml::table> root;
  if (diagnostics.readFile("camera path")) root = diagnostics.parse();
  renderers::TomlReader r(diagnostics);
  CameraPath out;
  if (root) {
    r.onlyKeys(*root, "", {"fps", "loop", "keyframe"});
    out.fps_ = r.number(*root, "fps", "", 30.0f);
    if (!(out.fps_ > 0 && out.fps_ <= 1000))
      r.problem(*root->get("fps"), "fps", "must be in (0, 1000]");
    out.loop_ = r.boolean(*root, "loop", "", false);
    const std::vector<const toml::table*> keys = r.arrayOfTables(*root, "keyframe");
    renderers::CameraDesc previous = sceneCamera;
    for (std::size_t i = 0; i < keys.size(); ++i)
      r.entry([&] {
        Key k;
        readKeyframe(r, *keys[i], static_cast<int>(i + 1), previous,
                     out.keys_.empty() ? 0.0 : out.keys_.back().time, out.keys_.empty(), k.camera,
                     k.time);
        if (const toml::node* step = keys[i]->get("step")) {
          const std::string field = "keyframe #" + std::to_string(i + 1) + ".step";
          const auto v = r.diagnostics().integer(*step, field);
          if (v && (*v < 0 || *v >= timeSteps))
            r.problem(*step, field,
                      timeSteps > 1 ? "must be from 0 to " + std::to_string(timeSteps - 1) +
                                          " (the scene's time steps), not " + std::to_string(*v)
                                    : std::string("is for a scene with a time series"));
          else if (v)
            k.step = static_cast<std::uint32_t>(*v);
        }
        previous = k.camera;
        out.keys_.push_back(k);
      });
    // (at() needs one; a file with problems is refused below anyway.)
    if (out.keys_.empty() && diagnostics.ok())
      r.problem(root->get("keyframe") ? *root->get("keyframe") : *root, "keyframe",
                "a camera path needs at least one [[keyframe]]");
  }
  diagnostics.throwIfAny();
  return out;
}

double CameraPath::timeOf(std::uint32_t frameId) const {
  double t = frameId > 0 ? double(frameId - 1) / fps_ : 0.0;
  if (loop_ && duration() > 0) t = std::fmod(t, duration());
  return t;
}

std::optional<std::uint32_t> CameraPath::stepAt(std::uint32_t frameId) const {
  const double t = timeOf(frameId);
  std::optional<std::uint32_t> step;
  for (const Key& k : keys_) {
    if (k.time > t) break;
    if (k.step) step = k.step;
  }
  return step;
}

renderers::CameraDesc CameraPath::at(std::uint32_t frameId) const {
  const double t = timeOf(frameId);
  if (t <= keys_.front().time) return keys_.front().camera;
  if (t >= keys_.back().time) return keys_.back().camera;
  const auto after = std::upper_bound(keys_.begin(), keys_.end(), t,
                                      [](double v, const Key& k) { return v < k.time; });
  const Key& a = *(after - 1);
  const Key& b = *after;
  const float s = static_cast<float>((t - a.time) / (b.time - a.time));
  renderers::CameraDesc c = a.camera;
  c.position = a.camera.position + (b.camera.position - a.camera.position) * s;
  c.lookAt = a.camera.lookAt + (b.camera.lookAt - a.camera.lookAt) * s;
  c.up = a.camera.up + (b.camera.up - a.camera.up) * s;
  c.fovY = a.camera.fovY + (b.camera.fovY - a.camera.fovY) * s;
  // Interpolating two valid cameras can pass through a degenerate one (up along the view):
  // keep the earlier keyframe's up then.
  if (renderers::length(renderers::cross(c.lookAt - c.position, c.up)) <= 0) c.up = a.camera.up;
  return c;
}

}  // namespace app
