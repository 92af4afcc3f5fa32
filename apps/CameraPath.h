#pragma once
// --camera-path FILE.toml: camera keyframes (time -> camera) for reproducible fly-throughs.
// Frame F is at time (F - 1) / fps, so a path gives the same camera for the same frame on any
// machine at any speed; between keyframes position, look-at, up and field of view are
// interpolated linearly; after the last keyframe the camera holds (or the path starts over,
// `loop = true`). configs/paths/orbit.toml shows and documents every field.
#include <cstdint>
#include <string>
#include <vector>

#include "renderers/Camera.h"

namespace app {

class CameraPath {
 public:
  // Reads `path`; keyframes may leave out up and fov (then `sceneCamera`'s). Throws
  // base::Error listing every problem, each naming the file, line, column and field.
  static CameraPath load(const std::string& path, const renderers::CameraDesc& sceneCamera);

  renderers::CameraDesc at(std::uint32_t frameId) const;
  double duration() const { return keys_.empty() ? 0 : keys_.back().time; }

 private:
  struct Key {
    double time = 0;
    renderers::CameraDesc camera;
  };
  std::vector<Key> keys_;
  double fps_ = 30;
  bool loop_ = false;
};

}  // namespace app
