#pragma once
// Internal to the volume sources: the OpenVDB reader lives in its own translation unit so that
// only it compiles OpenVDB's (heavy) headers. resolveOpenVdbGrid is declared in VolumeSource.h.
#include "renderers/scivis/io/VolumeLoad.h"

namespace renderers::scivis {

// The voxels of `box` of source.vdb's float grid (source.grid resolved): reads only the grid's
// leaf nodes that touch the box and samples them; inactive voxels get the grid's background.
Volume loadOpenVdbBox(const VolumeSource& source, const VoxelBox& box);

}  // namespace renderers::scivis
