#pragma once
// Reading a [[volumes]] entry and a transfer function from a scene file (SceneToml.cpp calls
// these). Every error names the file, line and field.
//
//   [[volumes]]
//   name = "wave"
//   source = "wavelet"            # wavelet | marschner-lobb | raw | openvdb
//   dims = [256, 256, 256]        # procedural: the resolution; raw: required
//   origin = [-1, -1, -1]         # optional; default: centred on 0
//   spacing = 0.0078              # number or [x, y, z]; default: longest side 2 world units
//   # wavelet: maximum, sigma, x_freq, x_mag, y_freq, y_mag, z_freq, z_mag
//   # marschner-lobb: f_m, alpha
//   # raw: file, type = "float32" | "uint8" | "uint16", byte_order = "little" | "big",
//   #      header_bytes
//   # openvdb: file, grid (default: the first float grid)
//   transfer_function = { preset = "cool-warm", range = [37, 277], opacity = [[37, 0], [277, 0.4]] }
//   # or colors = [[value, r, g, b], ...]; opacity_unit = world distance (default: min spacing)
#include <filesystem>
#include <string>

#include "renderers/TomlReader.h"
#include "renderers/scivis/SciVisDesc.h"
#include "renderers/scivis/TransferFunction.h"
#include "renderers/scivis/VolumeSource.h"

namespace renderers {

// `folder` resolves relative file names. The transfer function's range defaults to the source's
// value range where that is known without reading voxels (procedural fields), else it is required.
VolumeDesc readVolume(const TomlReader& r, const toml::table& t, const std::filesystem::path& folder);
TransferFunction readTransferFunction(const TomlReader& r, const toml::node& n,
                                      const std::string& what);

}  // namespace renderers
