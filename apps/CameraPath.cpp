#include "apps/CameraPath.h"

#include <algorithm>
#include <cmath>

#include "renderers/TomlReader.h"

namespace app {

CameraPath CameraPath::load(const std::string& path, const renderers::CameraDesc& sceneCamera) {
  renderers::TomlReader r(path);
  toml::table root;
  try {
    root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    // Line 0: the file could not be read at all.
    if (e.source().begin.line == 0)
      throw base::Error(path + ": cannot read the camera path (" + std::string(e.description()) +
                        ")");
    throw base::Error(path + ":" + std::to_string(e.source().begin.line) + ": " +
                      std::string(e.description()));
  }
  r.onlyKeys(root, "the camera path", {"fps", "loop", "keyframe"});
  CameraPath out;
  out.fps_ = r.number(root, "fps", "the camera path", 30.0f);
  if (!(out.fps_ > 0 && out.fps_ <= 1000)) r.fail(*root.get("fps"), "fps must be in (0, 1000]");
  out.loop_ = r.boolean(root, "loop", "the camera path", false);
  const std::vector<const toml::table*> keys = r.arrayOfTables(root, "keyframe");
  if (keys.empty()) throw base::Error(path + ":1: the camera path needs at least one [[keyframe]]");
  renderers::CameraDesc previous = sceneCamera;
  for (const toml::table* t : keys) {
    const std::string what = "keyframe";
    r.onlyKeys(*t, what, {"time", "position", "look_at", "up", "fov"});
    Key k;
    const toml::node& time = r.require(*t, "time", what);
    k.time = r.number(time, what + ".time");
    if (k.time < 0) r.fail(time, "keyframe.time must not be negative");
    if (!out.keys_.empty() && k.time <= out.keys_.back().time)
      r.fail(time, "keyframe.time must be later than the keyframe before");
    k.camera = sceneCamera;
    k.camera.position = r.vec3(r.require(*t, "position", what), what + ".position");
    k.camera.lookAt = r.vec3(r.require(*t, "look_at", what), what + ".look_at");
    // Up and fov carry over from the keyframe before (the scene's for the first).
    k.camera.up = r.vec3(*t, "up", what, previous.up);
    k.camera.fovY = r.number(*t, "fov", what, previous.fovY);
    if (!(k.camera.fovY >= 1 && k.camera.fovY <= 170))
      r.fail(*t->get("fov"), "keyframe.fov must be in [1, 170] degrees");
    const renderers::Vec3 view = k.camera.lookAt - k.camera.position;
    if (renderers::length(view) <= 0 || renderers::length(renderers::cross(view, k.camera.up)) <= 0)
      r.fail(*t, "keyframe: look_at must differ from position and not lie along up");
    previous = k.camera;
    out.keys_.push_back(k);
  }
  return out;
}

renderers::CameraDesc CameraPath::at(std::uint32_t frameId) const {
  double t = frameId > 0 ? double(frameId - 1) / fps_ : 0.0;
  if (loop_ && duration() > 0) t = std::fmod(t, duration());
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
