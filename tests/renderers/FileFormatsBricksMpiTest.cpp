// Volume files written by other programs render as their voxels given raw: a field written by
// nibabel (NIfTI-2, gzipped) and teem's unu (NRRD bzip2, detached ascii), and VTK's wavelet in 4
// pieces written by VTK's parallel writer (.pvti), each drawn with 4 bricks on 3 ranks (a volume
// and an isosurface, so bricks read their boxes and ghost shells of the file), give the same
// bytes as the raw voxels with 4 bricks on 1 rank.
#include <gtest/gtest.h>
#include <mpi.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "renderers/SceneToml.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"
#include "tests/MpiTestUtil.h"
#include "tests/renderers/BrickTestUtil.h"

namespace renderers::scivis {
namespace {

constexpr int kWidth = 64, kHeight = 48, kTile = 16;

// The folder rank 0 had the peers' tools write the files into (the same on every rank).
const std::string& filesFolder() {
  static const std::string folder = [] {
    char name[256] = {};
    if (testutil::worldRank() == 0) {
      char pattern[] = "/tmp/dfbwall-formats-bricks.XXXXXX";
      const std::string made = mkdtemp(pattern);
      const std::string command = std::string("/usr/bin/python3 ") + DFBWALL_PEER_WRITERS +
                                  " --scene-files " + made + " > " + made + "/writers.log 2>&1";
      if (std::system(command.c_str()) != 0)
        std::strcpy(name, "(the writers failed)");
      else
        std::strncpy(name, made.c_str(), sizeof name - 1);
    }
    MPI_Bcast(name, sizeof name, MPI_CHAR, 0, MPI_COMM_WORLD);
    return std::string(name);
  }();
  return folder;
}

// A scene drawing `volume` (TOML fields) as a volume and an isosurface at `iso`, the grid
// placed explicitly so every format's copy lies where the raw one does.
std::shared_ptr<SceneDesc> scene(const std::string& name, const std::string& volume, Index3 dims,
                                 float iso, float lo, float hi) {
  const std::string path = filesFolder() + "/" + name + ".toml";
  if (testutil::worldRank() == 0) {
    std::ofstream(path)
        << "[camera]\nposition = [70.0, 45.0, 80.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 40.0\n"
        << "[materials.shell]\ntype = \"diffuse\"\ncolor = [0.8, 0.9, 1.0]\nopacity = 0.4\n"
        << "[[volumes]]\nname = \"v\"\n"
        << volume << "\norigin = [" << -dims.x / 2 << ".0, " << -dims.y / 2 << ".0, " << -dims.z / 2
        << ".0]\nspacing = [1.0, 1.0, 1.0]\n"
        << "transfer_function = { preset = \"viridis\", range = [" << lo << ", " << hi
        << "], opacity = [[" << lo << ", 0.0], [" << hi << ", 0.3]] }\n"
        << "[[isosurfaces]]\nvolume = \"v\"\nvalue = " << iso << "\nmaterial = \"shell\"\n"
        << "[[lights]]\ntype = \"ambient\"\nintensity = 0.5\n"
        << "[[lights]]\ntype = \"directional\"\ndirection = [0.4, -0.6, -0.7]\n"
        << "[scivis]\nao_samples = 0\nshadows = false\n";
  }
  MPI_Barrier(MPI_COMM_WORLD);
  return std::make_shared<SceneDesc>(readSceneToml(path));
}

// 4 bricks on the first `ranks` ranks (rank 0's image; empty elsewhere).
std::vector<float> render(const std::shared_ptr<SceneDesc>& desc, int ranks) {
  return test::onFirstRanks(ranks, [&](MPI_Comm comm, int rank) {
    RenderSettings settings;
    settings.width = kWidth, settings.height = kHeight, settings.seed = 3;
    return test::renderHeldBricks(desc, settings, loadOwnBricks(*desc, 4, 1, rank, ranks), comm,
                                  kTile, 1, std::chrono::milliseconds(60000));
  });
}

// `extra`: more fields of the files' volumes.
void expectSameImage(const std::string& rawVolume, const std::vector<std::string>& files,
                     Index3 dims, float iso, float lo, float hi, const std::string& extra = "") {
  const std::vector<float> raw = render(scene("raw", rawVolume, dims, iso, lo, hi), 1);
  for (const std::string& file : files) {
    const std::vector<float> image =
        render(scene(file + "-scene", "source = \"file\"\nfile = \"" + file + "\"" + extra, dims,
                     iso, lo, hi),
               testutil::worldSize());
    if (testutil::worldRank() != 0) continue;
    ASSERT_EQ(image.size(), 4u * kWidth * kHeight);
    ASSERT_EQ(image.size(), raw.size());
    int lit = 0;
    for (std::size_t i = 0; i < raw.size(); i += 4)
      if (std::abs(raw[i] - raw[0]) > 0.05f) ++lit;
    EXPECT_GT(lit, kWidth * kHeight / 10) << "the volume should cover much of the image";
    EXPECT_EQ(0, std::memcmp(image.data(), raw.data(), raw.size() * sizeof(float)))
        << file << " with 4 bricks on " << testutil::worldSize()
        << " ranks differs from its voxels given raw on 1 rank";
    std::printf("%s: 4 bricks on %d ranks, the same bytes as raw on 1 rank\n", file.c_str(),
                testutil::worldSize());
  }
}

TEST(FileFormatsBricksMpi, PeerWrittenFilesRenderAsTheirRawVoxels) {
  ASSERT_EQ(filesFolder().front(), '/') << filesFolder();
  expectSameImage("source = \"raw\"\nfile = \"field.raw\"\ntype = \"float32\"\ndims = [48, 40, 32]",
                  {"field.nii.gz", "field.nrrd", "field.nhdr"}, {48, 40, 32}, 60.0f, 0.0f, 100.0f);
  expectSameImage(
      "source = \"raw\"\nfile = \"wavelet.raw\"\ntype = \"float32\"\ndims = [48, 40, 32]",
      {"wavelet.pvti"}, {48, 40, 32}, 160.0f, 40.0f, 270.0f, "\narray = \"RTData\"");
  if (testutil::worldRank() == 0) std::filesystem::remove_all(filesFolder());
}

}  // namespace
}  // namespace renderers::scivis
