// Prints voxel values of a volume file as dfbwall reads them, for tests that read the same file
// independently (volume_known_answers.py):
//   volume_probe FILE NAME i j k [i j k ...]
// NAME: the HDF5 dataset or NetCDF variable ("-" for none). One line per voxel: the value from
// a read of the whole grid, then from a read of a small brick around the voxel only, then the
// whole read's value range (NaN voxels left out).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "base/Error.h"
#include "renderers/scivis/io/VolumeLoad.h"
#include "renderers/scivis/io/formats/VolumeFile.h"

int main(int argc, char** argv) {
  using namespace renderers;
  using namespace renderers::scivis;
  if (argc < 6 || (argc - 3) % 3 != 0) {
    std::fprintf(stderr, "usage: volume_probe FILE NAME i j k [i j k ...]\n");
    return 2;
  }
  try {
    VolumeSource s;
    s.kind = VolumeSource::Kind::File;
    s.file.path = argv[1];
    const auto format = volumeFormatOfPath(s.file.path);
    if (!format) throw base::Error(s.file.path + ": unknown format");
    s.file.format = *format;
    const std::string name = argv[2];
    if (name != "-")
      (s.file.format == VolumeFormat::Hdf5 ? s.file.dataset : s.file.variable) = name;
    resolveVolumeFile(s);
    const Volume whole = loadVolume(s, s.grid.wholeBox());
    for (int a = 3; a + 2 < argc; a += 3) {
      const Index3 p{std::atoi(argv[a]), std::atoi(argv[a + 1]), std::atoi(argv[a + 2])};
      Index3 lo, hi;
      for (int axis = 0; axis < 3; ++axis) {
        const int l = std::max(0, p[axis] - 1), h = std::min(s.grid.dims[axis], p[axis] + 2);
        (axis == 0 ? lo.x : axis == 1 ? lo.y : lo.z) = l;
        (axis == 0 ? hi.x : axis == 1 ? hi.y : hi.z) = h;
      }
      const Volume brick = loadVolume(s, {lo, hi});
      std::printf("%.9g %.9g\n", whole.at(p.x, p.y, p.z), brick.at(p.x, p.y, p.z));
    }
    std::printf("range %.9g %.9g\n", whole.valueMin, whole.valueMax);
  } catch (const base::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
