#pragma once
// VTK XML image data: .vti (one piece) and .pvti (pieces in .vti files of their own), parsed with
// expat as far as the chosen point data array (or the appended data) and no further. A .vti's
// array becomes a StoredArray (ascii text, base64, appended raw or base64, zlib or LZ4 blocks);
// a .pvti's pieces are listed with their boxes and each is opened only by a read that meets it.
#include "renderers/VolumeSource.h"

namespace renderers::scivis {

// Fills source.grid, source.type and source.file.stored (.vti) or .pieces (.pvti) from the file
// (source.file.array names the point data array; empty: the first). Throws base::Error naming
// the file (and the XML's line) and the attribute on any problem; a missing piece file is one.
void resolveVtkImage(VolumeSource& source);
// The voxels of `box`, from the pieces that meet it.
Volume loadVtkImageBox(const VolumeSource& source, const VoxelBox& box);

}  // namespace renderers::scivis
