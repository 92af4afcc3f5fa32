#pragma once
// The scivis parts of a scene file, read into SceneDesc after its materials and meshes:
//
//   [[volumes]]      see VolumeToml.h
//   [[isosurfaces]]
//   volume = "wave"              # a [[volumes]] name
//   values = [120, 200]          # or value = 120
//   materials = ["a", "b"]       # one per value, or material = "a" for all
//   [[particles]]
//   name = "halo"; material = "white"; radius = 0.01 (all) or radii = [...] (one each)
//   centers = [[x, y, z], ...]   # inline, or
//   file = "p.raw"; layout = "xyzra"  # float32 records: position, radius (r), attribute (a)
//   generator = "clusters"; count = 100000; seed = 1; center = [0, 0, 0]; size = 2  # or
//   attribute = [...]; color_map = { preset = "viridis", range = [0, 1] }
//   [[lights]]
//   type = "directional" | "point" | "ambient"; direction / position; color; intensity
//   [scivis]
//   ao_samples = 4; ao_distance = 0.5; sampling_rate = 1.0; shadows = true
//   min_transmittance = 1e-3
#include <filesystem>

#include "renderers/SceneDesc.h"
#include "renderers/TomlReader.h"

namespace renderers::scivis {

// Appends the volumes, isosurfaces, particles and lights of `root` to `d` and reads its
// [scivis] settings; `d.materials` must already be read. Problems go to `r`, each entry read on
// its own.
void readSciVis(TomlReader& r, const toml::table& root, const std::filesystem::path& folder,
                SceneDesc& d);

}  // namespace renderers::scivis
