#pragma once
// Parts of a scene file the core does not read itself. A renderer kept in a folder of its own
// registers the top-level keys it reads and a reader for them, once, from the program's start
// (the scivis renderer: volumes, isosurfaces, particles, lights and [scivis];
// renderers/scivis/Registration.h). readSceneToml (SceneToml.h) accepts their keys and calls
// the readers, in the order they were registered, after the camera, materials and meshes.
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "renderers/SceneDesc.h"
#include "renderers/TomlReader.h"

namespace renderers {

struct SceneSections {
  std::vector<std::string> keys;  // the top-level keys `read` takes
  // What they describe to draw, for the error of a scene without anything to draw: "volumes or
  // particles" (read into SceneDesc::extensions, whose emptiness decides).
  std::string draws;
  // Appends what it reads of `root` to `d` (names in other files are relative to `folder`).
  // Problems go to `r` (TomlReader.h), which the caller throws at the end.
  std::function<void(TomlReader& r, const toml::table& root, const std::filesystem::path& folder,
                     SceneDesc& d)>
      read;
};

// Registers `sections`, replacing sections registered before with the same keys. Thread-safe.
void registerSceneSections(SceneSections sections);
// Everything registered, in order. Thread-safe.
std::vector<SceneSections> registeredSceneSections();

}  // namespace renderers
