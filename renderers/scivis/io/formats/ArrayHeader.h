#pragma once
// What the header of an NRRD, NIfTI-1/-2 or MetaImage file says: the grid and where its voxels are
// stored. The parsers take the first bytes of the file (for .nii.gz: of the inflated stream) and
// throw base::Error located in the file (line and column for text headers) and naming the field
// on anything they
// do not understand or do not believe (dims past the caps, sizes that overflow, unknown types or
// encodings). They never read files themselves, so the fuzzer runs them on any bytes.
#include <string>
#include <string_view>

#include "renderers/scivis/io/formats/StoredArray.h"

namespace renderers::scivis {

// Voxels per axis at most (as the scene file allows) and in all (2^34: 16 GiB of uint8).
constexpr int kMaxFileDims = 16384;
constexpr std::uint64_t kMaxFileVoxels = std::uint64_t{1} << 34;

struct ArrayHeader {
  Index3 dims;
  Vec3 spacing{1.0f};
  Vec3 origin{0.0f};
  StoredArray data;  // data.path: the data file (the header's own or a detached one)
};

// Text headers end at a blank line (NRRD) or the ElementDataFile line (MetaImage); a header not
// ended within this many bytes is refused.
constexpr std::size_t kMaxTextHeader = 1 << 20;

// `bytes`: the file's first bytes (up to kMaxTextHeader); `path`: the file, for messages and to
// resolve detached data files against its folder.
ArrayHeader parseNrrdHeader(std::string_view bytes, const std::string& path);
ArrayHeader parseMetaImageHeader(std::string_view bytes, const std::string& path);
// NIfTI-1 or NIfTI-2, a single file (.nii, magic "n+1"/"n+2") or a .hdr whose voxels are in the
// .img beside it ("ni1"/"ni2"): `bytes` at least the header (348 or 540 bytes); `compressed`: the
// file is gzipped (.nii.gz, .hdr.gz; bytes are then the inflated stream's first bytes). `time`
// selects the volume of a 4-D file.
constexpr std::size_t kNiftiHeaderBytes = 540;  // the larger, NIfTI-2's
ArrayHeader parseNiftiHeader(std::string_view bytes, const std::string& path, bool compressed,
                             int time = 0);

// The .img (.img.gz) beside a NIfTI .hdr (.hdr.gz); empty when `headerPath` is not named so.
std::string niftiImagePath(const std::string& headerPath);

// What is wrong with dims against the caps ("1 voxels along axis 1, must be ..."); empty when
// nothing is.
std::string fileDimsProblem(Index3 dims);

}  // namespace renderers::scivis
