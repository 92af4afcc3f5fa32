#pragma once
// --camera-path FILE.toml: camera keyframes (time -> camera) for reproducible fly-throughs.
// Frame F is at time (F - 1) / fps, so a path gives the same camera for the same frame on any
// machine at any speed; between keyframes position, look-at, up and field of view are
// interpolated linearly; after the last keyframe the camera holds (or the path starts over,
// `loop = true`). A keyframe may name a time step of the scene's series (`step = N`): frames from
// its time on show that step, until a later keyframe names another (steps are not interpolated).
// configs/paths/cornell-flyby.toml shows and documents every field.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "renderers/Camera.h"

namespace app {

class CameraPath {
 public:
  // Reads `path`; keyframes may leave out up and fov (then `sceneCamera`'s). Throws
  // base::Error listing every problem, each naming the file, line, column and field (a step
  // past the scene's `timeSteps` is one).
  static CameraPath load(const std::string& path, const renderers::CameraDesc& sceneCamera,
                         std::uint32_t timeSteps = 1);

  renderers::CameraDesc at(std::uint32_t frameId) const;
  // The time step frame `frameId` shows: the last keyframe's up to its time that names one;
  // nullopt before any does (or when none does).
  std::optional<std::uint32_t> stepAt(std::uint32_t frameId) const;
  double duration() const { return keys_.empty() ? 0 : keys_.back().time; }

 private:
  struct Key {
    double time = 0;
    renderers::CameraDesc camera;
    std::optional<std::uint32_t> step;
  };
  double timeOf(std::uint32_t frameId) const;
  std::vector<Key> keys_;
  double fps_ = 30;
  bool loop_ = false;
};

}  // namespace app
