#pragma once
// Where a volume's voxels come from, and making any sub-box of them. Procedural fields are
// evaluated only at the requested voxels; raw files are read only over the requested box (a
// rank keeping one brick never reads the whole file); OpenVDB grids are sampled into the box;
// NRRD, NIfTI, MetaImage, HDF5 and NetCDF files are read over the box only (compressed ones
// are streamed, everything outside the box discarded: renderers/scivis/formats/).
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "renderers/scivis/Volume.h"
#include "renderers/scivis/formats/StoredArray.h"

namespace renderers {

// VTK's vtkRTAnalyticSource ("Wavelet"): v = maximum * exp(-(x²+y²+z²) / (2 sigma²))
// + xMag sin(xFreq x) + yMag sin(yFreq y) + zMag cos(zFreq z) over its whole extent
// [-10, 10]³, with x = (centre - i) / extent width as VTK computes it. Any resolution samples
// that same extent (dims 21³ gives exactly VTK's values).
struct WaveletParams {
  float maximum = 255, sigma = 0.5f;
  float xFreq = 60, xMag = 10, yFreq = 30, yMag = 18, zFreq = 40, zMag = 5;
};

// Marschner & Lobb's test signal on [-1, 1]³:
// rho = (1 - sin(pi z / 2) + alpha (1 + cos(2 pi fM cos(pi r / 2)))) / (2 (1 + alpha)),
// r = sqrt(x² + y²).
struct MarschnerLobbParams {
  float fM = 6, alpha = 0.25f;
};

struct RawFileParams {
  std::string path;  // as given, resolved against the scene file's folder
  bool bigEndian = false;
  std::uint64_t headerBytes = 0;  // skipped at the start of the file
};

struct OpenVdbParams {
  std::string path;
  std::string gridName;  // empty: the first float grid in the file
  // The OpenVDB index coordinate of voxel (0, 0, 0): the minimum of the grid's active bounding
  // box. Filled in by resolveOpenVdbGrid with the grid.
  Index3 indexOrigin;
};

enum class VolumeFormat { Nrrd, Nifti, MetaImage, Hdf5, NetCdf };

// A volume file in one of the formats above (source = "file").
struct VolumeFileParams {
  std::string path;
  VolumeFormat format = VolumeFormat::Nrrd;
  std::string dataset;   // HDF5: the dataset's path (empty: the file's only 3-D/4-D dataset)
  std::string variable;  // NetCDF: the variable (empty: the file's only 3-D/4-D variable)
  int time = 0;          // 4-D data (t, z, y, x): the time step
  // Filled in by resolveVolumeFile from the header:
  StoredArray stored;              // NRRD, NIfTI, MetaImage: where the voxels are
  std::vector<double> missing;     // HDF5, NetCDF: _FillValue / missing_value (become NaN)
  float slope = 1, intercept = 0;  // NetCDF scale_factor / add_offset
  bool hasGeometry = false;        // the file places its grid (spacing, origin); HDF5 does not
};

struct VolumeSource {
  enum class Kind { Wavelet, MarschnerLobb, RawFile, OpenVdb, File };
  Kind kind = Kind::Wavelet;
  // The whole field's grid, resolved when the source is read (defaults filled in), so every
  // rank knows every volume's geometry without touching voxels.
  GridGeometry grid;
  VoxelType type = VoxelType::Float32;  // of the produced voxels; procedural fields: Float32
  WaveletParams wavelet;
  MarschnerLobbParams marschnerLobb;
  RawFileParams raw;
  OpenVdbParams vdb;
  VolumeFileParams file;
};

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

}  // namespace renderers
