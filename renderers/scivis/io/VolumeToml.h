#pragma once
// Reading a [[volumes]] entry and a transfer function from a scene file (SceneToml.cpp calls
// these). Problems go to the reader, each naming the file, line, column and field.
//
//   [[volumes]]
//   name = "wave"
//   source = "wavelet"            # wavelet | marschner-lobb | raw | openvdb | file
//   dims = [256, 256, 256]        # 2 to 16384 per axis. raw: required; wavelet: default VTK's
//                                 # [21, 21, 21]; marschner-lobb: default [40, 40, 40];
//                                 # openvdb: not allowed (the grid's active bounding box)
//   origin = [-1, -1, -1]         # optional; default: centred on 0 (openvdb: the file's)
//   spacing = 0.0078              # > 0, number or [x, y, z]; default: longest side 2 world units
//                                 # (openvdb: the file's voxel size)
//   visible = true                # false: only for isosurfaces, never volume-rendered
//   # wavelet: maximum, sigma (> 0), x_freq, x_mag, y_freq, y_mag, z_freq, z_mag
//   # marschner-lobb: f_m, alpha (>= 0)
//   # raw: file (required), type = "float32" | "uint8" | "uint16" (required),
//   #      byte_order = "little" (default) | "big", header_bytes (default 0); the file's size
//   #      must be header_bytes + dims x type size exactly (checked when the scene is read)
//   # openvdb: file (required), grid (default: the first float grid); the file's metadata is
//   #      read with the scene (geometry), its voxels only by loadVolume
//   # file: file (required; .nrrd .nhdr .nii .nii.gz .mhd .mha .h5 .hdf5 .nc .cdf; .raw and
//   #      .vdb are read as source = "raw" / "openvdb" with their fields), format =
//   #      "nrrd" | "nifti" | "metaimage" | "hdf5" | "netcdf" (default: from the name),
//   #      dataset (HDF5) / variable (NetCDF) (default: the file's only 3-D/4-D one), time
//   #      (4-D data, default 0); dims, type and (except HDF5) spacing and origin come from the
//   #      file's header, read with the scene; spacing/origin here override them
//   #      A time series: file a printf pattern ("step-%03d.nrrd", with time_steps) or a glob,
//   #      or time_steps along a 4-D file's time dimension; first_step, fps (steps a second,
//   #      0: one a frame). Every step's header is read here: a missing step or one whose dims
//   #      or type differ from the first is an error naming it (docs/scivis.md, "Time series")
//   transfer_function = { preset = "cool-warm", range = [37, 277], opacity = [[37, 0], [277, 0.4]]
//   } # preset: cool-warm | viridis | inferno | grayscale | rainbow, or # colors = [[value, r, g,
//   b], ...] (r, g, b in [0, 1]); exactly one of the two. # opacity = [[value, opacity], ...]
//   (opacity in [0, 1]); default: a ramp from 0 at the #   range's low end to max_opacity (default
//   1) at its high end. # Control point values ascend (two equal values make a step). # range =
//   [low, high], low < high; default: a procedural field's known range #   (knownValueRange), else
//   the colour/opacity points' span; a preset on a file needs it. # opacity_unit = world distance
//   the opacities are for (> 0; default: the smallest spacing). # No transfer_function: cool-warm
//   over a procedural field's range; files need one unless # visible = false.
#include <filesystem>
#include <optional>
#include <string>
#include <utility>

#include "renderers/TomlReader.h"
#include "renderers/TransferFunction.h"
#include "renderers/scivis/io/SciVisDesc.h"
#include "renderers/scivis/io/VolumeLoad.h"

namespace renderers::scivis {

// `folder` resolves relative file names. The transfer function's range defaults to the source's
// value range where that is known without reading voxels (procedural fields), else it is required.
VolumeDesc readVolume(TomlReader& r, const toml::table& t, const std::filesystem::path& folder);
TransferFunction readTransferFunction(TomlReader& r, const toml::node& n, const std::string& what);
// The same, with the range used when the table gives none (a volume's known value range).
TransferFunction readTransferFunction(TomlReader& r, const toml::node& n, const std::string& what,
                                      std::optional<std::pair<float, float>> defaultRange);

}  // namespace renderers::scivis
