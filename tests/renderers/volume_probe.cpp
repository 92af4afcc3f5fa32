// Prints voxel values of a volume file as dfbwall reads them, for tests that read the same file
// independently (volume_known_answers.py):
//   volume_probe FILE NAME i j k [i j k ...]
// NAME: the HDF5 dataset, NetCDF variable or VTK array ("-" for none). One line per voxel: the
// value from a read of the whole grid, then from a read of a small brick around the voxel only,
// then the whole read's value range (NaN voxels left out).
//   volume_probe --dump FILE NAME OUT
// writes every voxel of a whole read to OUT as float32 (x fastest) after checking that reads of
// the eight octants (as bricks are read) equal it, and prints the dims, spacing and origin.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "base/Error.h"
#include "renderers/scivis/io/VolumeLoad.h"
#include "renderers/scivis/io/formats/VolumeFile.h"

namespace {

using namespace renderers;
using namespace renderers::scivis;

VolumeSource resolved(const std::string& path, const std::string& name) {
  VolumeSource s;
  s.kind = VolumeSource::Kind::File;
  s.file.path = path;
  const auto format = volumeFormatOfPath(s.file.path);
  if (!format) throw base::Error(s.file.path + ": unknown format");
  s.file.format = *format;
  if (name != "-")
    (s.file.format == VolumeFormat::Hdf5  ? s.file.dataset
     : s.file.format == VolumeFormat::Vtk ? s.file.array
                                          : s.file.variable) = name;
  resolveVolumeFile(s);
  return s;
}

int dump(const std::string& path, const std::string& name, const std::string& out) {
  const VolumeSource s = resolved(path, name);
  const Index3 d = s.grid.dims;
  const Volume whole = loadVolume(s, s.grid.wholeBox());
  for (int octant = 0; octant < 8; ++octant) {
    Index3 lo, hi;
    for (int a = 0; a < 3; ++a) {
      const int half = d[a] / 2, upper = (octant >> a) & 1;
      (a == 0 ? lo.x : a == 1 ? lo.y : lo.z) = upper ? std::max(0, half - 1) : 0;
      (a == 0 ? hi.x : a == 1 ? hi.y : hi.z) = upper ? d[a] : std::min(d[a], half + 1);
    }
    const Volume part = loadVolume(s, {lo, hi});
    for (int k = lo.z; k < hi.z; ++k)
      for (int j = lo.y; j < hi.y; ++j)
        for (int i = lo.x; i < hi.x; ++i) {
          const float a = whole.at(i, j, k), b = part.at(i, j, k);
          if (!(a == b || (std::isnan(a) && std::isnan(b)))) {
            std::fprintf(stderr, "octant %d voxel (%d, %d, %d): %.9g, the whole read %.9g\n",
                         octant, i, j, k, b, a);
            return 1;
          }
        }
  }
  FILE* f = std::fopen(out.c_str(), "wb");
  if (!f) throw base::Error(out + ": cannot write");
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const float v = whole.at(i, j, k);
        std::fwrite(&v, 4, 1, f);
      }
  std::fclose(f);
  std::printf("dims %d %d %d spacing %.9g %.9g %.9g origin %.9g %.9g %.9g\n", d.x, d.y, d.z,
              s.grid.spacing.x, s.grid.spacing.y, s.grid.spacing.z, s.grid.origin.x,
              s.grid.origin.y, s.grid.origin.z);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 5 && std::string(argv[1]) == "--dump") {
    try {
      return dump(argv[2], argv[3], argv[4]);
    } catch (const base::Error& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 1;
    }
  }
  if (argc < 6 || (argc - 3) % 3 != 0) {
    std::fprintf(stderr, "usage: volume_probe FILE NAME i j k [i j k ...]\n");
    return 2;
  }
  try {
    const VolumeSource s = resolved(argv[1], argv[2]);
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
