#pragma once
// A dense voxel array stored in a file (x fastest, then y, then z), or in a list of files, and
// reading any box of it. The NRRD, NIfTI, MetaImage and VTK readers describe their data with
// one. Raw data is read with pread over the box's rows only, base64 text (VTK) by decoding just
// the box's bytes; streams (zlib/gzip, bzip2, NRRD's ascii and hex text, VTK's compressed
// blocks) are decoded in order and everything outside the box is discarded as it passes (never
// held; VTK's blocks before the box are jumped, not decompressed).
//
// File types the renderer does not hold are converted on load, values kept: uint8 and uint16
// stay as they are; int8, int16, uint32, int32, float64 become float32 (exact for int8, int16
// and integers up to 2^24; float64 rounds to the nearest float32). A scale (NIfTI scl_slope /
// scl_inter) makes float32 of any type.
#include <cstdint>
#include <string>

#include "renderers/Volume.h"
#include "renderers/VolumeSource.h"

namespace renderers::scivis {

std::size_t fileTypeBytes(FileType type);
const char* fileTypeName(FileType type);  // "int8", "uint8", ..., "float64"

// What a stored array becomes in memory (see above).
VoxelType heldVoxelType(const StoredArray& array);

// Raw arrays: throws base::Error naming the file when it is missing or shorter than the
// `dims` voxels need. Compressed arrays: only that the file opens (its length shows on reading).
void checkStoredArray(const StoredArray& array, Index3 dims);

// The voxels of `box` of the array whose whole grid is `grid`, converted to heldVoxelType.
// Throws base::Error naming the file on a short file, a stream that ends early or corrupt
// compressed data.
Volume readStoredBox(const StoredArray& array, const GridGeometry& grid, const VoxelBox& box);

// Bytes read from volume files on this thread (raw or compressed); volumeFileBytesRead() adds
// these.
std::uint64_t storedBytesRead();

}  // namespace renderers::scivis
