// Hostile volume files (truncated, lying headers, huge dims, a gzip bomb, wrong types): each
// gives one error naming the file, fast, with no crash.
#include <gtest/gtest.h>

#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include "base/Error.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/RenderScene.h"
#include "renderers/scivis/io/VolumeLoad.h"
#include "renderers/scivis/io/formats/VolumeFile.h"
#include "renderers/scivis/scene/VolumeField.h"
#include "tests/renderers/RenderTestUtil.h"
#include "tests/renderers/VolumeFileTestUtil.h"

namespace renderers::scivis {
namespace {

using namespace volfiletest;

// ---- hostile files: one error naming the file, fast, no crash ------------------------------

std::string errorOf(const fs::path& path, bool loadToo = true) {
  const auto start = std::chrono::steady_clock::now();
  std::string message = "(no error)";
  try {
    const VolumeSource s = fileSource(path);
    if (loadToo) loadVolume(s, {{0, 0, 0}, s.grid.dims});
  } catch (const base::Error& e) {
    message = e.what();
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 2.0) << path;
  return message;
}

void expectError(const std::string& name, const std::string& bytes, const std::string& says) {
  writeFile(folder() / name, bytes);
  const std::string message = errorOf(folder() / name);
  EXPECT_NE(message.find(says), std::string::npos) << name << ": " << message;
  if (says != "(no error)") {
    EXPECT_NE(message.find(name), std::string::npos) << "the error names the file: " << message;
  }
}

TEST(VolumeFile, HostileFilesGiveOneErrorNamingTheFile) {
  const std::string nrrd = "NRRD0004\ndimension: 3\n";
  const std::string u8 = voxelBytesOf<std::uint8_t>(false, true);
  expectError("short.nrrd", nrrd + "type: uchar\nsizes: 13 9 7\n\n" + u8.substr(0, 100),
              "shorter than the 868 the header calls for");
  expectError("huge.nrrd", nrrd + "type: uchar\nsizes: 13 9 70000\n\n" + u8, "more than the cap");
  expectError("total.nrrd", nrrd + "type: uchar\nsizes: 16000 16000 16000\n\n",
              "voxels, more than");
  // Header problems are located at the value: file, line and column.
  expectError("type.nrrd", nrrd + "type: block\nsizes: 13 9 7\n\n",
              "type.nrrd:3:7: field 'type': 'block' is not one dfbwall reads");
  expectError("enc.nrrd", nrrd + "type: uchar\nencoding: zstd\nsizes: 13 9 7\n\n",
              "enc.nrrd:4:11: field 'encoding': 'zstd' is not one dfbwall reads (raw, gzip, bzip2, "
              "ascii, hex)");
  expectError("dim.nrrd", "NRRD0004\ndimension: 4\n", "dimension 4");
  expectError("junk.nrrd", nrrd + "sizes: 13 9 x7\n",
              "junk.nrrd:3:13: field 'sizes': 'x7' is not a number");
  expectError("line.nrrd", nrrd + "type: uchar\nsizes 13 9 7\n",
              "line.nrrd:4:1: 'sizes 13 9 7' is not a 'field: value' line");
  expectError("endian.nrrd", nrrd + "type: short\nsizes: 13 9 7\n\n", "misses field 'endian'");
  expectError("nomagic.nrrd", "PK\3\4", "not an NRRD file");
  expectError("endsearly.nrrd",
              nrrd + "type: uchar\nencoding: gzip\nsizes: 13 9 7\n\n" + gzipped(u8.substr(0, 500)),
              "ends after 500 bytes");
  expectError("corrupt.nrrd",
              nrrd + "type: uchar\nencoding: gzip\nsizes: 13 9 7\n\n" + std::string(300, 'z'),
              "corrupt");
  // A gzip bomb: 32 MiB of zeros behind a header asking for 819 bytes: reading stops there.
  expectError("bomb.nrrd",
              nrrd + "type: uchar\nencoding: gzip\nsizes: 13 9 7\n\n" +
                  gzipped(std::string(32u << 20, '\0')),
              "(no error)");
  expectError("bomb2.nrrd",
              nrrd + "type: uchar\nencoding: gzip\nsizes: 1000 1000 40\n\n" +
                  gzipped(std::string(16u << 20, '\0')),
              "ends after 16777216 bytes");
  const std::string nifti = niftiHeader(kDims, 2, 8);
  expectError("trunc.nii", nifti.substr(0, 200), "too short for a NIfTI-1 header");
  expectError("short.nii", nifti + u8.substr(0, 10), "shorter than");
  std::string lying = nifti;
  lying[70] = 77;  // datatype 77: no such type
  expectError("type.nii", lying + u8, "'datatype' 77");
  std::string big = nifti;
  const std::int16_t huge = 30000;
  for (int a = 0; a < 3; ++a) std::memcpy(big.data() + 42 + 2 * a, &huge, 2);
  expectError("huge.nii", big, "must be between 2 and 16384");
  std::string magic = nifti;
  magic[345] = 'i';
  expectError("magic.nii", magic + u8, "'magic'");
  expectError("notgz.nii.gz", gzipped(nifti + u8).substr(0, 300), "ends after");
  expectError("nometa.mha", "ObjectType = Image\nNDims = 3\nDimSize = 13 9 7\n", "ElementDataFile");
  expectError("metatype.mha",
              "NDims = 3\nDimSize = 13 9 7\nElementType = MET_STRING\nElementDataFile = LOCAL\n",
              "metatype.mha:3:15: field 'ElementType': 'MET_STRING' is not one dfbwall reads");
  expectError("nofile.mhd",
              "NDims = 3\nDimSize = 13 9 7\nElementType = MET_UCHAR\nElementDataFile = gone.raw\n",
              "nofile.mhd: its data file");
  expectError("garbage.h5", "not an hdf5 file at all", "cannot open as an HDF5 file");
  expectError("garbage.nc", "CDF\1 lies", "has 0 3-D/4-D variables");
  // Wrong types: a NetCDF text variable; an HDF5 file with only a 2-D dataset.
  {
    const fs::path p = folder() / "text.nc";
    int nc, d[3], v;
    nc_create(p.c_str(), NC_CLOBBER, &nc);
    nc_def_dim(nc, "z", 2, &d[0]), nc_def_dim(nc, "y", 2, &d[1]), nc_def_dim(nc, "x", 2, &d[2]);
    nc_def_var(nc, "words", NC_CHAR, 3, d, &v);
    nc_close(nc);
    const std::string m = errorOf(p);
    EXPECT_NE(m.find("text.nc: variable 'words': the variable's type is not one"),
              std::string::npos)
        << m;
  }
  {
    const fs::path p = folder() / "flat.h5";
    const hid_t f = H5Fcreate(p.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    const hsize_t d2[2] = {4, 4};
    const hid_t space = H5Screate_simple(2, d2, nullptr);
    H5Dclose(H5Dcreate2(f, "/image", H5T_IEEE_F32LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    H5Sclose(space);
    H5Fclose(f);
    const std::string m = errorOf(p);
    EXPECT_NE(m.find("flat.h5: the file has 0 3-D/4-D datasets"), std::string::npos) << m;
  }
}

// The newer encodings and formats: text that is not numbers, hex that is not hex, a bzip2
// stream that is not one, lists that name the wrong number of files, VTK files that lie.
TEST(VolumeFile, HostileEncodingsListsAndVtkFilesGiveOneNamedError) {
  const std::string nrrd = "NRRD0004\ndimension: 3\nsizes: 3 2 2\n";
  expectError("text.nrrd", nrrd + "type: short\nencoding: ascii\n\n1 2 3 4 5 6 7 8 9 10 11 70000\n",
              "value 12, '70000', is not an integer that fits int16");
  expectError("fewtext.nrrd", nrrd + "type: float\nencoding: ascii\n\n1 2 3\n",
              "the text data ends after 12 bytes");
  expectError("word.nrrd", nrrd + "type: float\nencoding: txt\n\n1 2 x3\n", "'x3', is not");
  expectError("hex.nrrd", nrrd + "type: uchar\nencoding: hex\n\n00 01 0g\n",
              "'g' after 2 bytes, not a hex digit");
  expectError("bz.nrrd", nrrd + "type: uchar\nencoding: bzip2\n\nBZh9 not really bzip2 at all",
              "bzip2 volume data is corrupt");
  expectError("skip.nrrd", nrrd + "type: uchar\nencoding: gzip\nbyte skip: -1\n\n",
              "is for raw data only, not gzip");
  writeFile(folder() / "s0.raw", std::string(6, '\1'));
  expectError("list.nhdr", nrrd + "type: uchar\ndata file: LIST\ns0.raw\n",
              "field 'data file': the list names 1 files, the sizes and subdim 2 call for 2");
  expectError("gone.nhdr", nrrd + "type: uchar\ndata file: s%d.raw 0 1 1\n", "s1.raw: cannot open");
  expectError("format.nhdr", nrrd + "type: uchar\ndata file: s%d%d.raw 0 1 1\n",
              "one integer conversion");
  expectError("lines.nhdr", nrrd + "type: uchar\nline skip: 5\ndata file: s0.raw\n",
              "ends after 0 lines, before the 5 its header skips");
  // NIfTI-2: a header cut short, and a .hdr whose .img is missing.
  std::string nifti2(540, '\0');
  const std::int32_t size = 540;
  std::memcpy(nifti2.data(), &size, 4);
  expectError("cut.nii", nifti2.substr(0, 400), "too short for a NIfTI-2 header (540 bytes)");
  std::memcpy(nifti2.data() + 4, "ni2\0", 4);
  const std::int64_t dims[4] = {3, 4, 4, 4};
  std::memcpy(nifti2.data() + 16, dims, sizeof dims);
  const std::int16_t uint8Type = 2;
  std::memcpy(nifti2.data() + 12, &uint8Type, 2);
  expectError("alone.hdr", nifti2, "alone.img: cannot open");
  // VTK: no such array (the ones there are listed), a block header that lies, a missing piece,
  // appended raw data cut short, XML that does not parse.
  const std::string vtkHead =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" "
      "byte_order=\"LittleEndian\" header_type=\"UInt32\"";
  const std::string image =
      ">\n<ImageData WholeExtent=\"0 2 0 1 0 1\" Origin=\"0 0 0\" Spacing=\"1 1 1\">\n"
      "<Piece Extent=\"0 2 0 1 0 1\">\n<PointData>\n";
  writeFile(folder() / "name.vti",
            vtkHead + image +
                "<DataArray type=\"UInt8\" Name=\"a\" format=\"ascii\">0 1 2 3 4 5 6 7 8 9 10 "
                "11</DataArray></PointData></Piece></ImageData></VTKFile>\n");
  {
    VolumeSource named;
    named.kind = VolumeSource::Kind::File;
    named.file.path = (folder() / "name.vti").string();
    named.file.format = VolumeFormat::Vtk;
    named.file.array = "b";
    std::string message = "(no error)";
    try {
      resolveVolumeFile(named);
    } catch (const base::Error& e) {
      message = e.what();
    }
    EXPECT_NE(message.find("name.vti: no point data array named 'b' (point data arrays: a)"),
              std::string::npos)
        << message;
  }
  const std::string appended =
      "<DataArray type=\"UInt8\" Name=\"a\" format=\"appended\" offset=\"0\"/></PointData>"
      "</Piece></ImageData><AppendedData encoding=\"raw\">\n _";
  expectError("short.vti", vtkHead + image + appended + std::string("\x0c\0\0\0\1\2", 6),
              "shorter than");
  std::string lying = std::string("\1\0\0\0\x0c\0\0\0\x0c\0\0\0\x09\0\0\0", 16) + "not zlib!";
  expectError("lying.vti",
              vtkHead + " compressor=\"vtkZLibDataCompressor\"" + image + appended + lying,
              "compressed block 0 is corrupt");
  expectError("bad.vti", vtkHead + image + "<DataArray <<", "not VTK XML");
  expectError("pieces.pvti",
              "<VTKFile type=\"PImageData\"><PImageData WholeExtent=\"0 2 0 1 0 1\">"
              "<PPointData><PDataArray type=\"UInt8\" Name=\"a\"/></PPointData>"
              "<Piece Extent=\"0 2 0 1 0 1\" Source=\"nowhere.vti\"/></PImageData></VTKFile>",
              "piece 'nowhere.vti' is missing");
}

}  // namespace
}  // namespace renderers::scivis
