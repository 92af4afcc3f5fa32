#pragma once
// Volume files (source = "file"): which format a file is, reading its header into the source's
// grid and type, and loading any box of its voxels. Dispatches to the NRRD / NIfTI / MetaImage
// header parsers (ArrayHeader.h, voxels through StoredArray) and to the HDF5 and NetCDF readers.
#include <optional>
#include <string>

#include "renderers/VolumeSource.h"

namespace renderers::scivis {

// From the file name: .nrrd/.nhdr, .nii/.nii.gz/.hdr/.hdr.gz, .mhd/.mha, .h5/.hdf5/.he5,
// .nc/.cdf/.nc4, .vti/.pvti.
std::optional<VolumeFormat> volumeFormatOfPath(const std::string& path);
// "nrrd", "nifti", "metaimage", "hdf5", "netcdf", "vtk"; nullopt for anything else.
std::optional<VolumeFormat> volumeFormatNamed(const std::string& name);
const char* volumeFormatName(VolumeFormat format);

// Reads the header of source.file (path and format set) and fills in source.grid (dims; spacing
// and origin from the file where it places its grid, see VolumeFileParams::hasGeometry),
// source.type (what the voxels are held as) and source.file's resolved fields. Reads no voxels.
// Throws base::Error naming the file (and the header's line and field) on any problem.
void resolveVolumeFile(VolumeSource& source);

// The voxels of `box` of a resolved file source. Missing values (NetCDF/HDF5 _FillValue and
// missing_value) become NaN, which renders as empty space.
Volume loadVolumeFile(const VolumeSource& source, const VoxelBox& box);

}  // namespace renderers::scivis
