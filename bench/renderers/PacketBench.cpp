// Primary rays per second: rtcIntersect1 against rtcIntersect8/16 packets of 4x2 / 4x4 pixels,
// over the same camera rays, on the renderers' TBB workers. Decided that packets pay here: the
// renderers trace camera rays as 4x4 packets (renderers/PixelBlocks.h).
//   packet_bench SCENE SIZE THREADS
#include <embree3/rtcore.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "base/Parallel.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/Camera.h"
#include "renderers/Scene.h"
#include "renderers/scivis/Registration.h"

using namespace renderers;
using namespace renderers::scivis;

template <int N, typename RayHitN, typename Fn>
double run(const Scene& scene, const Camera& cam, int size, int pw, Fn intersect) {
  const auto t0 = std::chrono::steady_clock::now();
  std::atomic<long> hits{0};
  base::parallelFor(static_cast<std::size_t>(size / (N / pw)), [&](std::size_t row) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    long h = 0;
    for (int x0 = 0; x0 < size; x0 += pw) {
      alignas(64) RayHitN rh;
      alignas(64) int valid[N];
      for (int i = 0; i < N; ++i) {
        Vec3 o, d;
        cam.ray(float(x0 + i % pw) + 0.5f, float(row * (N / pw) + i / pw) + 0.5f, 0.5f, 0.5f, o, d);
        valid[i] = -1;
        rh.ray.org_x[i] = o.x, rh.ray.org_y[i] = o.y, rh.ray.org_z[i] = o.z;
        rh.ray.dir_x[i] = d.x, rh.ray.dir_y[i] = d.y, rh.ray.dir_z[i] = d.z;
        rh.ray.tnear[i] = 0, rh.ray.tfar[i] = 1e30f, rh.ray.time[i] = 0, rh.ray.mask[i] = ~0u;
        rh.ray.id[i] = 0, rh.ray.flags[i] = 0;
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
      }
      intersect(valid, scene.embreeScene(), &ctx, &rh);
      for (int i = 0; i < N; ++i) h += rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
    }
    hits += h;
  });
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return double(size) * size / s;
}

int main(int argc, char** argv) {
  renderers::scivis::registerSciVis();  // scenes may have volumes, isosurfaces and particles
  if (argc < 4) return std::fprintf(stderr, "usage: %s SCENE SIZE THREADS\n", argv[0]), 2;
  const Scene scene(loadSceneDesc(argv[1]));
  const int size = std::atoi(argv[2]);
  base::ThreadLimit limit(std::atoi(argv[3]));
  const Camera cam(scene.desc().camera, size, size);
  auto one = [](int* valid, RTCScene s, RTCIntersectContext* c, RTCRayHit8* rh) {
    // The same rays one at a time: unpack each lane into an RTCRayHit.
    for (int i = 0; i < 8; ++i) {
      if (!valid[i]) continue;
      RTCRayHit r;
      r.ray = {rh->ray.org_x[i],
               rh->ray.org_y[i],
               rh->ray.org_z[i],
               0,
               rh->ray.dir_x[i],
               rh->ray.dir_y[i],
               rh->ray.dir_z[i],
               0,
               1e30f,
               ~0u,
               0,
               0};
      r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(s, c, &r);
      rh->hit.geomID[i] = r.hit.geomID;
    }
  };
  auto p8 = [](int* v, RTCScene s, RTCIntersectContext* c, RTCRayHit8* rh) {
    rtcIntersect8(v, s, c, rh);
  };
  auto p16 = [](int* v, RTCScene s, RTCIntersectContext* c, RTCRayHit16* rh) {
    rtcIntersect16(v, s, c, rh);
  };
  for (int rep = 0; rep < 2; ++rep) {  // the first round warms caches and threads
    const double a = run<8, RTCRayHit8>(scene, cam, size, 4, one);
    const double b = run<8, RTCRayHit8>(scene, cam, size, 4, p8);
    const double c = run<16, RTCRayHit16>(scene, cam, size, 4, p16);
    if (rep)
      std::printf(
          "{\"scene\": \"%s\", \"size\": %d, \"threads\": %s, \"single_Mrays_s\": %.2f, "
          "\"packet8_Mrays_s\": %.2f, \"packet16_Mrays_s\": %.2f}\n",
          argv[1], size, argv[3], a / 1e6, b / 1e6, c / 1e6);
  }
}
