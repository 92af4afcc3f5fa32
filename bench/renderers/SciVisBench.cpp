// The scivis renderer on the wavelet, one process: frame time, camera rays/s and volume
// samples/s, with the image as a PNG to put beside VTK's (bench/renderers/vtk_volume.py renders
// the same field, transfer function, camera and sample spacing).
//   scivis_bench MODE RESOLUTION SIZE THREADS FRAMES [OUT.png | OUT.f32 (raw linear floats)]
// MODE: "volume"  the wavelet as a volume (VTK's comparison: blue-white-red over 37..277,
//                 opacity ramp 0..0.4 per voxel, one sample per voxel, no shading)
//       "volume-uint8", "volume-uint16"  the same volume stored as integers (uint8: value - 30,
//                 uint16: value x 200, rounded; written to a raw file in $TMPDIR or /tmp, read
//                 back), its transfer function moved along: the march on integer voxels
//       "iso"     two opaque isosurfaces (160, 215, as configs/scenes/wavelet256-contours.toml),
//                 no shadows or AO: what a camera ray costs to find an isosurface
//       "iso-ao"  two opaque isosurfaces with 4 ambient-occlusion rays and shadows per hit
// Isosurfaces are triangles made at load (load_s includes them; isosurface_s: polygonising and
// BVHs); ns_per_camera_ray is per thread (frame time x threads / rays).
// The camera is VTK's ResetCamera() view of the volume (view angle 30°, looking down -z),
// turned about the volume's centre by 360/FRAMES degrees a frame; the result is the median.
// Cost per volume sample: "ns_per_volume_sample" is wall time x threads / samples (per core);
// "cpu_ns_per_volume_sample" is the process's CPU time / samples, which other processes on a
// shared machine disturb less ("median_cpu_frame_s" likewise beside "median_frame_s"; VTK's
// script reports the same two). The environment variable SCIVIS_MARCH=sse|avx2|avx512 picks the
// volume march's kernel (default: the fastest the CPU runs), to compare them in one build.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "base/Error.h"
#include "renderers/CanvasImage.h"
#include "renderers/RenderScene.h"
#include "renderers/scivis/BuiltinScenes.h"
#include "renderers/scivis/Registration.h"
#include "renderers/scivis/io/VolumeLoad.h"
#include "renderers/scivis/render/SciVisRenderer.h"
#include "wall/image/Png.h"

namespace {

using namespace renderers;
using namespace renderers::scivis;

// The volume's voxels as integers in a raw file (see "volume-uint8" above), the transfer
// function's values moved the same way.
void toIntegers(VolumeDesc& v, VoxelType type) {
  const VolumeSource wavelet = v.source;
  const bool u8 = type == VoxelType::UInt8;
  const float offset = u8 ? -30.0f : 0.0f, scale = u8 ? 1.0f : 200.0f;
  const char* tmp = std::getenv("TMPDIR");
  const std::string path = std::string(tmp && *tmp ? tmp : "/tmp") + "/scivis_bench-" +
                           std::to_string(::getpid()) + "-" + voxelTypeName(type) + ".raw";
  {
    std::ofstream out(path, std::ios::binary);
    const Index3 n = wavelet.grid.dims;
    std::vector<char> row(static_cast<std::size_t>(n.x) * voxelBytes(type));
    for (int k = 0; k < n.z; ++k)
      for (int j = 0; j < n.y; ++j) {
        for (int i = 0; i < n.x; ++i) {
          const float value = (proceduralValue(wavelet, i, j, k) + offset) * scale;
          const long u = std::lround(std::clamp(value, 0.0f, u8 ? 255.0f : 65535.0f));
          if (u8) {
            row[static_cast<std::size_t>(i)] = static_cast<char>(u);
          } else {
            const std::uint16_t w = static_cast<std::uint16_t>(u);
            std::memcpy(&row[2 * static_cast<std::size_t>(i)], &w, 2);  // little-endian (x86)
          }
        }
        out.write(row.data(), static_cast<std::streamsize>(row.size()));
      }
    if (!out) throw base::Error("scivis_bench: cannot write " + path);
  }
  v.source.kind = VolumeSource::Kind::RawFile;
  v.source.type = type;
  v.source.raw = {path, false, 0};
  for (auto& c : v.transfer.colors) c.first = (c.first + offset) * scale;
  for (auto& o : v.transfer.opacities) o.first = (o.first + offset) * scale;
  v.transfer.valueMin = (v.transfer.valueMin + offset) * scale;
  v.transfer.valueMax = (v.transfer.valueMax + offset) * scale;
}

SceneDesc benchScene(const std::string& mode, int resolution) {
  SceneDesc d = waveletScene(resolution);
  VolumeDesc& v = sciVisDesc(d).volumes[0];
  v.transfer.colors = {{37.0f, {0.23f, 0.30f, 0.75f}},
                       {157.0f, {0.87f, 0.87f, 0.87f}},
                       {277.0f, {0.71f, 0.02f, 0.15f}}};
  sciVisDesc(d).isosurfaces.clear();
  sciVisDesc(d).settings = {};
  // VTK's fixed-point caster stops a ray when its remaining opacity drops below 0xff of 0x7fff.
  sciVisDesc(d).settings.minTransmittance = 1.0f / 128.0f;
  d.environment = {};
  // VTK's ResetCamera: the bounding sphere fills a 30° view, looking down -z.
  const float radius = std::sqrt(3.0f), distance = radius / std::sin(15.0f * kPi / 180.0f);
  d.camera = {{0, 0, distance}, {0, 0, 0}, {0, 1, 0}, 30.0f, 0, 0};
  if (mode.rfind("volume", 0) == 0) {
    v.transfer.opacities = {{37.0f, 0.0f}, {277.0f, 0.4f}};
    if (mode != "volume")
      toIntegers(v, mode == "volume-uint8" ? VoxelType::UInt8 : VoxelType::UInt16);
  } else if (mode == "iso") {
    v.visible = false;
    Material a{"a", MaterialType::Diffuse, {0.55f, 0.7f, 1.0f}, {}, 0, 1.5f};
    Material b{"b", MaterialType::Diffuse, {1.0f, 0.55f, 0.2f}, {}, 0, 1.5f};
    d.materials = {a, b};
    sciVisDesc(d).isosurfaces = {{0, 160.0f, 0}, {0, 215.0f, 1}};
    sciVisDesc(d).settings.shadows = false;
  } else {
    v.visible = false;
    Material a{"a", MaterialType::Diffuse, {0.9f, 0.9f, 0.95f}, {}, 0, 1.5f};
    Material b{"b", MaterialType::Diffuse, {1.0f, 0.55f, 0.2f}, {}, 0, 1.5f};
    d.materials = {a, b};
    sciVisDesc(d).isosurfaces = {{0, 145.0f, 0}, {0, 215.0f, 1}};
    sciVisDesc(d).settings.aoSamples = 4;
    sciVisDesc(d).settings.aoDistance = 0.3f;
  }
  return d;
}

double processCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double loadAverage() {
  std::ifstream in("/proc/loadavg");
  double load = -1;
  in >> load;
  return load;
}

MarchKernel marchFromEnvironment() {
  const char* name = std::getenv("SCIVIS_MARCH");
  const std::string n = name ? name : "auto";
  if (n == "sse") return MarchKernel::Sse;
  if (n == "avx2") return MarchKernel::Avx2;
  if (n == "avx512") return MarchKernel::Avx512;
  if (n == "auto") return MarchKernel::Auto;
  throw base::Error("SCIVIS_MARCH: '" + n + "' is none of sse, avx2, avx512, auto");
}

}  // namespace

int main(int argc, char** argv) {
  renderers::scivis::registerSciVis();  // scenes may have volumes, isosurfaces and particles
  if (argc < 6) {
    std::fprintf(stderr,
                 "usage: %s volume|volume-uint8|volume-uint16|iso|iso-ao RESOLUTION SIZE THREADS "
                 "FRAMES [OUT.png]\n",
                 argv[0]);
    return 2;
  }
  try {
    using Clock = std::chrono::steady_clock;
    const std::string mode = argv[1];
    const int resolution = std::atoi(argv[2]), size = std::atoi(argv[3]);
    const int threads = std::atoi(argv[4]), frames = std::max(1, std::atoi(argv[5]));
    const auto t0 = Clock::now();
    const SceneDesc desc = benchScene(mode, resolution);
    const RenderScene scene = buildRenderScene("scivis", desc);
    if (sciVisDesc(desc).volumes[0].source.kind == VolumeSource::Kind::RawFile)
      std::remove(
          sciVisDesc(desc).volumes[0].source.raw.path.c_str());  // read: the voxels are in memory
    const double loadS = std::chrono::duration<double>(Clock::now() - t0).count();
    RenderSettings settings;
    settings.width = settings.height = size;
    settings.seed = 1;
    // One turn over the frames, as dfbwall's --orbit 360/FRAMES.
    const float orbitDegreesPerFrame = 360.0f / static_cast<float>(frames);
    const MarchKernel march = resolveMarchKernel(marchFromEnvironment());
    auto renderer =
        std::make_unique<SciVisRenderer>(sciVisScene(scene), settings, SciVisOptions{true, march});
    const SciVisRenderer* scivis = renderer.get();
    std::vector<double> seconds, cpuSeconds;
    std::vector<float> image;
    const std::uint64_t samplesBefore = scivis->volumeSamples();
    const double cpuBefore = processCpuSeconds();
    for (int f = 1; f <= frames; ++f) {
      renderer->beginFrame(
          {static_cast<std::uint32_t>(f), static_cast<std::uint32_t>(f)},
          orbitCamera(scene.desc->camera, orbitDegreesPerFrame * static_cast<float>(f - 1)));
      const auto a = Clock::now();
      const double cpuStart = processCpuSeconds();
      renderCanvas(*renderer, size, size, 64, threads, 1, image);
      seconds.push_back(std::chrono::duration<double>(Clock::now() - a).count());
      cpuSeconds.push_back(processCpuSeconds() - cpuStart);
    }
    const double samples = static_cast<double>(scivis->volumeSamples() - samplesBefore);
    const double cpu = processCpuSeconds() - cpuBefore;
    double total = 0;
    for (double s : seconds) total += s;
    std::vector<double> sorted = seconds;
    std::sort(sorted.begin(), sorted.end());
    const double median = sorted[sorted.size() / 2];
    std::sort(cpuSeconds.begin(), cpuSeconds.end());
    const double medianCpu = cpuSeconds[cpuSeconds.size() / 2];
    if (argc > 6) {
      // Frame 1's view (the last frame rendered is frame `frames`, one step short of a turn).
      renderer->beginFrame({1, 1}, scene.desc->camera);
      image = renderCanvas(*renderer, size, size, 64, threads, 1);
      const std::string out = argv[6];
      if (out.size() > 4 && out.compare(out.size() - 4, 4, ".f32") == 0) {
        // The linear floats as they are, to check that an optimisation changes no bit.
        if (std::FILE* f = std::fopen(out.c_str(), "wb")) {
          std::fwrite(image.data(), sizeof(float), image.size(), f);
          std::fclose(f);
        }
      }
      std::vector<std::uint32_t> rgba8(static_cast<std::size_t>(size) * size);
      for (std::size_t i = 0; i < rgba8.size(); ++i) {
        std::uint32_t p = 0;
        for (int c = 0; c < 4; ++c) {
          // Colours as they are, clamped, no display encoding: VTK writes its colours so.
          const float v = c == 3 ? 1.0f : std::clamp(image[4 * i + c], 0.0f, 1.0f);
          p |= static_cast<std::uint32_t>(std::lround(v * 255)) << (8 * c);
        }
        rgba8[i] = p;
      }
      if (out.size() > 4 && out.compare(out.size() - 4, 4, ".png") == 0)
        wall::writePng(out, rgba8.data(), size, size);
    }
    const SciVisScene::IsosurfaceStats& iso = sciVisScene(scene).isosurfaceStats();
    const double rays = double(size) * size * frames;
    std::printf(
        "{\"mode\": \"%s\", \"resolution\": %d, \"size\": %d, \"threads\": %d, \"frames\": %d, "
        "\"load_s\": %.3f, \"isosurface_s\": %.3f, \"isosurface_triangles\": %zu, "
        "\"median_frame_s\": %.4f, \"median_cpu_frame_s\": %.4f, \"min_frame_s\": %.4f, "
        "\"camera_rays_per_s\": %.4g, \"ns_per_camera_ray\": %.1f, "
        "\"volume_samples_per_s\": %.4g, \"volume_samples_per_ray\": %.1f, "
        "\"ns_per_volume_sample\": %.2f, \"cpu_ns_per_volume_sample\": %.2f, \"march\": \"%s\", "
        "\"load\": %.2f}\n",
        mode.c_str(), resolution, size, threads, frames, loadS, iso.seconds,
        iso.cameraTriangles + iso.shadingTriangles, median, medianCpu, sorted.front(), rays / total,
        1e9 * total * threads / rays, samples / total, samples / rays,
        samples > 0 ? 1e9 * total * threads / samples : 0.0,
        samples > 0 ? 1e9 * cpu / samples : 0.0, marchKernelName(march), loadAverage());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scivis_bench: %s\n", e.what());
    return 1;
  }
}
