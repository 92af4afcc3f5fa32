// libFuzzer target: volume files as dfbwall reads them. The first byte picks the format (NRRD,
// MetaImage, NIfTI, gzipped NIfTI, VTK .vti), the rest is the file: its header is parsed and, when
// it asks for at most 2^20 voxels, every voxel is read (raw data with pread, compressed data
// through the streaming inflater). Problems are base::Error, never a crash or a hang.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>

#include "renderers/scivis/io/VolumeLoad.h"
#include "renderers/scivis/io/formats/VolumeFile.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const std::string folder = [] {
    char pattern[] = "/tmp/dfbwall-fuzz-volume.XXXXXX";
    return std::string(mkdtemp(pattern));
  }();
  static const char* const names[] = {"v.nrrd", "v.mha", "v.nii", "v.nii.gz", "v.vti"};
  // A new name per input: nothing read from one input's file is resumed on the next.
  static std::uint64_t count = 0;
  const std::string path = folder + "/" + std::to_string(count++) + names[data[0] % 5];
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data + 1, 1, size - 1, f);
  std::fclose(f);
  try {
    renderers::VolumeSource s;
    s.kind = renderers::VolumeSource::Kind::File;
    s.file.path = path;
    s.file.format = *renderers::scivis::volumeFormatOfPath(path);
    renderers::scivis::resolveVolumeFile(s);
    if (s.grid.wholeBox().voxelCount() <= (std::size_t{1} << 20))
      (void)renderers::scivis::loadVolume(s, s.grid.wholeBox());
  } catch (const std::exception&) {
  }
  std::remove(path.c_str());
  return 0;
}
