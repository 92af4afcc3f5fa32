#pragma once
// Where a volume's voxels come from, as plain data a scene description holds: a procedural
// field, a raw file, an OpenVDB grid or a volume file. Reading them:
// renderers/scivis/io/VolumeLoad.h.
#include <cstdint>
#include <string>
#include <vector>

#include "renderers/Volume.h"

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

// A dense voxel array stored in a file (x fastest, then y, then z), raw, as a compressed stream
// or as text: what the NRRD, NIfTI, MetaImage and VTK readers find in a header
// (renderers/scivis/io/formats/StoredArray.h reads it). NRRD may spread it over a list of files,
// each holding the next `voxelsPerFile` voxels (its slices or rows).
enum class FileType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
// Zlib: a zlib or gzip stream (either, detected); Ascii: numbers as text; Hex: two hex digits
// a byte; Base64: base64 text (VTK); ZlibBlocks, Lz4Blocks: VTK's compressed arrays, a header of
// block sizes then blocks compressed one by one (raw, or base64 when `base64`).
enum class Encoding { Raw, Zlib, Bzip2, Ascii, Hex, Base64, ZlibBlocks, Lz4Blocks };

struct StoredArray {
  std::string path;                 // the file holding the voxels (the first of a list)
  std::vector<std::string> paths;   // a list of data files (NRRD); empty: `path` alone
  std::uint64_t voxelsPerFile = 0;  // a list: the voxels each of its files holds
  std::uint64_t lineSkip = 0;       // lines before fileOffset in each file (NRRD line skip)
  std::uint64_t fileOffset = 0;     // where the voxels, the stream or the text start
  std::uint64_t byteSkip = 0;       // bytes after the skipped lines (NRRD byte skip)
  bool atEnd = false;               // raw: the voxels end the file (NRRD byte skip -1)
  std::uint64_t streamSkip = 0;     // compressed, base64: decoded bytes before voxel 0
  Encoding encoding = Encoding::Raw;
  bool base64 = false;       // blocks: stored as base64 text
  int blockHeaderBytes = 4;  // blocks: the width of the header's numbers (UInt32, UInt64)
  FileType type = FileType::UInt8;
  bool bigEndian = false;
  float slope = 1, intercept = 0;  // value = stored * slope + intercept
  bool scaled() const { return slope != 1.0f || intercept != 0.0f; }
  bool compressed() const { return encoding == Encoding::Zlib || encoding == Encoding::Bzip2; }
  // Read in order only (decoded as it passes), not at any offset.
  bool streamed() const { return encoding != Encoding::Raw && encoding != Encoding::Base64; }
};

enum class VolumeFormat { Nrrd, Nifti, MetaImage, Hdf5, NetCdf, Vtk };

// A piece of a volume stored in a file of its own (VTK's .pvti): its box of the whole grid.
struct FilePiece {
  VoxelBox box;
  std::string path;
};

// A volume file in one of the formats above (source = "file").
struct VolumeFileParams {
  std::string path;
  VolumeFormat format = VolumeFormat::Nrrd;
  std::string dataset;   // HDF5: the dataset's path (empty: the file's only 3-D/4-D dataset)
  std::string variable;  // NetCDF: the variable (empty: the file's only 3-D/4-D variable)
  std::string array;     // VTK: the point data array (empty: the first)
  int time = 0;          // 4-D data (t, z, y, x): the time step
  // Filled in by resolveVolumeFile from the header:
  StoredArray stored;              // NRRD, NIfTI, MetaImage, .vti: where the voxels are
  std::vector<FilePiece> pieces;   // .pvti: the pieces (each read as a .vti where it meets a box)
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

}  // namespace renderers
