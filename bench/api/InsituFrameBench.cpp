// The in-situ frame of bench/insitu_languages.py from C++: each rank borrows its slab of a G^3
// radial field (the same bytes in every language), and every frame gives it again and renders
// it with the camera a step further round (a new scene version: value ranges, macrocells and the
// isosurface rebuilt). Render rank 0 prints one JSON line, {"language": "c++", "frame_ms": [...],
// "cpu_ms": [...], "calls_ms": [...]}: the wall time of clear_bricks + add_brick + render_frame
// per frame, the process's CPU time in it (all its threads: less hit by other programs' load)
// and the wall time of clear_bricks + add_brick alone (the calls whose cost is the language's
// own, rendering aside), and writes the last image.
//   mpirun -np R insitu_frame_bench GRID FRAMES WIDTHxHEIGHT IMAGE.png
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "api/DataDistributed.h"

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_MULTIPLE, &provided);
  int code = 0;
  try {
    if (argc != 5) throw std::runtime_error("usage: insitu_frame_bench GRID FRAMES WxH IMAGE");
    const int g = std::atoi(argv[1]), frames = std::atoi(argv[2]);
    int width = 0, height = 0;
    if (g < 8 || frames < 1 || std::sscanf(argv[3], "%dx%d", &width, &height) != 2)
      throw std::runtime_error("insitu_frame_bench: GRID >= 8, FRAMES >= 1, WxH");
    int rank = 0, ranks = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    // This rank's slab: planes [z0, z1] clip, voxels 2 below and 3 above where the field has them.
    const int z0 = (g - 1) * rank / ranks, z1 = (g - 1) * (rank + 1) / ranks;
    const int lo = std::max(0, z0 - 2), hi = std::min(g, z1 + 4);
    std::vector<float> u(static_cast<std::size_t>(hi - lo) * g * g);
    const double c = (g - 1) / 2.0;
    std::size_t n = 0;
    for (int z = lo; z < hi; ++z)
      for (int y = 0; y < g; ++y)
        for (int x = 0; x < g; ++x)
          u[n++] = static_cast<float>(((x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c)) /
                                      (3 * c * c));

    dfbwall::SessionOptions o;
    o.width = width, o.height = height, o.threads = 1, o.timeoutSeconds = 120;
    dfbwall::Session session(MPI_COMM_WORLD, o);
    dfbwall::Style st;
    dfbwall::VolumeStyle v;
    v.grid.dims = {g, g, g};
    v.transferFunction = "viridis";
    v.maxOpacity = 0.05f;
    v.autoRange = false;
    v.valueMin = 0, v.valueMax = 1;
    st.volumes.push_back(v);
    st.isosurfaces.push_back({0, 0.3f, {1.0f, 0.85f, 0.4f}, 1.0f});
    st.seed = 7;
    session.setStyle(st);
    dfbwall::Brick b;
    b.id = rank;
    b.boundsLo = {0, 0, static_cast<float>(z0)};
    b.boundsHi = {static_cast<float>(g - 1), static_cast<float>(g - 1), static_cast<float>(z1)};
    dfbwall::VolumePart part;
    part.lo = {0, 0, lo};
    part.hi = {g, g, hi};
    part.voxels = u.data();
    part.borrowed = true;
    b.volumes.push_back(part);
    std::string times, cpu, calls;
    for (int f = 0; f < frames; ++f) {
      const double a = 0.1 * f, r = 2.2 * g;
      dfbwall::Camera cam;
      cam.position = {static_cast<float>(c + r * std::sin(a)), static_cast<float>(c + 0.5 * r),
                      static_cast<float>(c - r * std::cos(a))};
      cam.lookAt = {static_cast<float>(c), static_cast<float>(c), static_cast<float>(c)};
      cam.fovY = 40;
      session.setCamera(cam);
      const auto t0 = std::chrono::steady_clock::now();
      const std::clock_t c0 = std::clock();
      session.clearBricks();
      session.addBrick(b);
      const double added =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      session.renderFrame();
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      times += (f ? ", " : "") + std::to_string(ms);
      calls += (f ? ", " : "") + std::to_string(added);
      cpu += (f ? ", " : "") + std::to_string(1e3 * double(std::clock() - c0) / CLOCKS_PER_SEC);
    }
    session.writeImage(argv[4]);
    session.close();
    if (rank == 0)
      std::printf(
          "{\"language\": \"c++\", \"frame_ms\": [%s], \"cpu_ms\": [%s], "
          "\"calls_ms\": [%s]}\n",
          times.c_str(), cpu.c_str(), calls.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    code = 1;
  }
  MPI_Finalize();
  return code;
}
