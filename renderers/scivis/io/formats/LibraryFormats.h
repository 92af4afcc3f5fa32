#pragma once
// HDF5 and NetCDF volumes through their own libraries: each rank opens the file itself and
// reads its box as a hyperslab (H5Dread) or with nc_get_vara, so it never reads more than its
// brick. Datasets and variables are 3-D (z, y, x: x varies fastest, as the volume's voxels) or
// 4-D (t, z, y, x; `time` picks the step). Errors name the file and list the datasets or
// variables that do exist. Serial HDF5 is not thread-safe: every call holds one lock.
#include <cstdint>
#include <string>
#include <vector>

#include "renderers/VolumeSource.h"

namespace renderers::scivis {

void resolveHdf5(VolumeSource& source);
Volume loadHdf5Box(const VolumeSource& source, const VoxelBox& box);
void resolveNetCdf(VolumeSource& source);
Volume loadNetCdfBox(const VolumeSource& source, const VoxelBox& box);

// Shared by both readers. "a, b, c" (or "none"): the datasets or variables a file has, for
// messages.
std::string listedNames(const std::vector<std::string>& names);
// Refuses a rank other than 3 (z, y, x) or 4 (t, z, y, x); `what` names the dataset or variable.
void checkArrayRank(int rank, const std::string& what);
// The grid dims (x, y, z) of a 3-D or 4-D array with extents `len` (`rank` of them, slowest
// first) after checking `time` against its time steps (4-D) or 0 (3-D) and the caps.
Index3 arrayGridDims(const std::uint64_t* len, int rank, int time, const std::string& what);
// Float voxels equal to one of `missing` become NaN, then
// value * slope + intercept; the range is updated.
void markMissing(Volume& v, const std::vector<double>& missing, float slope, float intercept);
// What a stored type with the given missing values and scale is held as (as StoredArray's rule;
// any missing value makes float32).
VoxelType heldTypeOf(FileType type, bool anyMissing, bool scaled);

}  // namespace renderers::scivis
