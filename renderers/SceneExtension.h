#pragma once
// What a renderer kept in a folder of its own adds to a scene description, beside the core's
// materials, meshes, spheres, camera and environment (the scivis renderer: volumes,
// isosurfaces, particles and lights). SceneDesc holds it by the renderer's name without knowing
// its type; the renderer's sections of the scene file (SceneSections.h) and its built-in scenes
// fill it, its own folder reads it back.
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace renderers {

class SceneExtension {
 public:
  virtual ~SceneExtension() = default;
  // A deep copy: a description copied is independent of the original.
  virtual std::unique_ptr<SceneExtension> clone() const = 0;
  // Whether it holds nothing to draw (a scene with nothing at all is refused).
  virtual bool empty() const = 0;
  // The files it refers to and the bytes it holds, for SceneDesc::inputFiles and bytes.
  virtual std::vector<std::string> inputFiles() const = 0;
  virtual std::uint64_t bytes() const = 0;
};

// A description's extensions by renderer name, copied deeply with it.
class SceneExtensions {
 public:
  SceneExtensions() = default;
  SceneExtensions(const SceneExtensions& other);
  SceneExtensions& operator=(const SceneExtensions& other);
  SceneExtensions(SceneExtensions&&) noexcept = default;
  SceneExtensions& operator=(SceneExtensions&&) noexcept = default;
  ~SceneExtensions() = default;

  // Renderer `name`'s extension, or null.
  const SceneExtension* find(const std::string& name) const;
  SceneExtension* find(const std::string& name);
  // Sets renderer `name`'s extension, replacing the one it had; returns it.
  SceneExtension& set(const std::string& name, std::unique_ptr<SceneExtension> extension);

  // The names of the renderers whose extension holds something to draw, in name order.
  std::vector<std::string> drawnBy() const;
  // Every extension's input files, in name order, and their bytes.
  std::vector<std::string> inputFiles() const;
  std::uint64_t bytes() const;

 private:
  std::map<std::string, std::unique_ptr<SceneExtension>> byName_;
};

}  // namespace renderers
