// Samples per second of a renderer on one process, tiles in parallel as the frame driver renders
// them, and optionally the image as a PPM (clamped, sRGB-encoded) to look at.
//   render_bench SCENE WIDTH HEIGHT SPP MAX_PATH_LENGTH THREADS [RENDERER] [OUT.ppm]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>

#include "renderers/BuiltinScenes.h"
#include "renderers/CanvasImage.h"
#include "renderers/Scene.h"
#include "renderers/scivis/Registration.h"

int main(int argc, char** argv) {
  renderers::scivis::registerSciVis();  // scenes may have volumes, isosurfaces and particles
  if (argc < 7) {
    std::fprintf(stderr, "usage: %s SCENE W H SPP MAX_PATH_LENGTH THREADS [RENDERER] [OUT.ppm]\n",
                 argv[0]);
    return 2;
  }
  try {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    const renderers::Scene scene(renderers::loadSceneDesc(argv[1]));
    const auto t1 = Clock::now();
    // Process CPU time as well as wall time: on a shared machine the wall time of a 2-thread
    // run swings with the other load, CPU seconds per sample much less.
    const std::clock_t c1 = std::clock();
    const int w = std::atoi(argv[2]), h = std::atoi(argv[3]), threads = std::atoi(argv[6]);
    const auto spp = static_cast<std::uint32_t>(std::atoi(argv[4]));
    const std::string name = argc > 7 ? argv[7] : "pathtracer";
    auto renderer = renderers::makeRenderer(name, scene, {w, h, 1, std::atoi(argv[5])});
    const auto image = renderers::renderCanvas(*renderer, w, h, 64, threads, spp);
    const auto t2 = Clock::now();
    const double cpu = double(std::clock() - c1) / CLOCKS_PER_SEC;
    const double load = std::chrono::duration<double>(t1 - t0).count();
    const double render = std::chrono::duration<double>(t2 - t1).count();
    const double samples = double(w) * h * spp;
    std::printf(
        "{\"scene\": \"%s\", \"renderer\": \"%s\", \"size\": [%d, %d], \"spp\": %u, "
        "\"threads\": %d, \"load_s\": %.3f, \"render_s\": %.3f, "
        "\"samples_per_s\": %.0f, \"cpu_s\": %.3f, \"samples_per_cpu_s\": %.0f}\n",
        argv[1], name.c_str(), w, h, spp, threads, load, render, samples / render, cpu,
        samples / cpu);
    if (argc > 8) {
      FILE* f = std::fopen(argv[8], "wb");
      std::fprintf(f, "P6\n%d %d\n255\n", w, h);
      for (std::size_t i = 0; i < image.size(); i += 4)
        for (int c = 0; c < 3; ++c) {
          const float v = std::clamp(image[i + c], 0.0f, 1.0f);
          const float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1 / 2.4f) - 0.055f;
          std::fputc(static_cast<int>(s * 255.0f + 0.5f), f);
        }
      std::fclose(f);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
