#pragma once
// Making any sub-box of a volume's voxels from its source (renderers/VolumeSource.h).
// Procedural fields are evaluated only at the requested voxels; raw files are read only
// over the requested box (a rank keeping one brick never reads the whole file); OpenVDB
// grids are sampled into the box; NRRD, NIfTI, MetaImage, HDF5 and NetCDF files are read
// over the box only (compressed ones are streamed, everything outside the box discarded:
// renderers/scivis/io/formats/).
#include <cstdint>
#include <optional>
#include <utility>

#include "renderers/Volume.h"
#include "renderers/VolumeSource.h"

namespace renderers::scivis {

// The field's value at whole-field voxel (i, j, k) of a procedural source (Wavelet,
// MarschnerLobb); for tests that compare against the formula.
float proceduralValue(const VolumeSource& source, int i, int j, int k);

// Raw files: the file size the grid, type and header call for. checkRawFile throws
// base::Error naming the file, the expected size and the found one when the file is
// missing or its size differs (a wrong dims/type/header would read garbage).
std::uint64_t expectedRawFileBytes(const VolumeSource& source);
void checkRawFile(const VolumeSource& source);

// OpenVDB files: reads the metadata only (no voxels) of source.vdb's grid (or of the first float
// grid when gridName is empty, then filling gridName in) and sets source.grid from its active
// bounding box and its transform: dims = the box's size (at least 2 per axis), spacing = the
// voxel size, origin = the world position of the box's minimum. Throws base::Error naming
// the file for a missing file or grid, a non-float grid, an empty grid or a rotated transform.
void resolveOpenVdbGrid(VolumeSource& source);

// The value range of a procedural field, known without making the volume: Marschner-Lobb
// [0, 1] (its bounds); the wavelet's range sampled at the volume's resolution but at most 129
// points per axis (at 21³ exactly VTK's 37.35 to 276.83; from 129³ up within 0.1% of the
// finest sampling's 33.95 to 286.2). Files: nullopt.
std::optional<std::pair<float, float>> knownValueRange(const VolumeSource& source);

// Bytes this thread has read from volume files through loadVolume so far: lets tests prove
// that a brick reads its own voxels and nothing else.
std::uint64_t volumeFileBytesRead();

// The voxels of `box` (non-empty, inside source.grid.wholeBox()). Throws base::Error
// naming the file and what is wrong on any I/O problem (missing, too short, unreadable).
Volume loadVolume(const VolumeSource& source, const VoxelBox& box);

}  // namespace renderers::scivis
