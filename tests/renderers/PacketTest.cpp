// Embree's 16-wide packet kernels against its single-ray kernel. The renderers trace camera rays
// in packets (renderers/PixelBlocks.h) and promise pixels that do not depend on which other rays
// share a packet; so every active lane of Scene::intersect(RayPacket) must be, bit for bit, what
// Scene::intersect gives that ray alone, whatever the other lanes hold and whichever are active.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "renderers/BuiltinScenes.h"
#include "renderers/Camera.h"
#include "renderers/MeshImport.h"
#include "renderers/Rng.h"
#include "renderers/Scene.h"
#include "tests/renderers/RenderTestUtil.h"

namespace renderers {
namespace {

constexpr int kLanes = RayPacket::kSize;

bool same(float a, float b) {
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}
bool same(Vec3 a, Vec3 b) { return same(a.x, b.x) && same(a.y, b.y) && same(a.z, b.z); }

// Traces `rays` as a packet and each active lane alone; returns a description of the first lane
// that differs ("" when none) and counts the lanes that hit something.
std::string compareLanes(const Scene& scene, const RayPacket& rays, int& hitLanes) {
  PacketHits packet;
  scene.intersect(rays, packet);
  for (int i = 0; i < kLanes; ++i) {
    std::ostringstream where;
    where << "lane " << i << " origin (" << rays.origin[i].x << ", " << rays.origin[i].y << ", "
          << rays.origin[i].z << ") direction (" << rays.direction[i].x << ", "
          << rays.direction[i].y << ", " << rays.direction[i].z << "): ";
    if (!rays.active[i]) {
      if (packet.found[i]) return where.str() + "inactive lane reports a hit";
      continue;
    }
    Hit single;
    const bool found = scene.intersect(rays.origin[i], rays.direction[i], 0.0f,
                                       std::numeric_limits<float>::infinity(), single);
    if (found != packet.found[i]) return where.str() + "hit in one kernel only";
    if (!found) continue;
    ++hitLanes;
    const Hit& p = packet.hit[i];
    if (!same(p.t, single.t) || !same(p.position, single.position) ||
        !same(p.normal, single.normal) || p.material != single.material ||
        p.light != single.light) {
      std::ostringstream d;
      d.precision(9);
      d << "t " << p.t << " vs " << single.t << ", material " << p.material->name << " vs "
        << single.material->name << ", light " << p.light << " vs " << single.light;
      return where.str() + d.str();
    }
  }
  return "";
}

// Active masks that exercise the packet kernels' paths: all lanes, one lane (Embree switches to
// single-ray traversal inside a packet when few lanes are active), and random subsets.
void setMask(RayPacket& rays, int pattern, const Sampler& random) {
  for (int i = 0; i < kLanes; ++i) {
    if (pattern == 0)
      rays.active[i] = true;
    else if (pattern == 1)
      rays.active[i] = i == pattern % kLanes + 4;
    else
      rays.active[i] = random.get(100 + i) < 0.5f;
  }
}

// Every 4x4 block of a w x h camera image, jittered as the path tracer jitters, under every
// mask pattern; then the same number of incoherent packets (random origins near the scene and
// random directions).
void checkScene(const Scene& scene, const CameraDesc& cameraDesc, int w, int h, Vec3 centre,
                float radius) {
  const Camera camera(cameraDesc, w, h);
  int hitLanes = 0, packets = 0;
  RayPacket rays;
  for (int by = 0; by < h; by += 4) {
    for (int bx = 0; bx < w; bx += 4) {
      for (int pattern = 0; pattern < 3; ++pattern) {
        const Sampler random(7, bx, by, 0, static_cast<std::uint32_t>(pattern));
        for (int i = 0; i < kLanes; ++i) {
          const Sampler s(7, bx + i % 4, by + i / 4, 0, static_cast<std::uint32_t>(pattern));
          camera.ray(static_cast<float>(bx + i % 4) + s.get(0),
                     static_cast<float>(by + i / 4) + s.get(1), s.get(2), s.get(3), rays.origin[i],
                     rays.direction[i]);
        }
        setMask(rays, pattern, random);
        const std::string diff = compareLanes(scene, rays, hitLanes);
        ASSERT_EQ(diff, "") << "camera block (" << bx << ", " << by << ")";
        ++packets;
      }
    }
  }
  for (int p = 0; p < packets; ++p) {
    const Sampler random(11, p, 0, 0, 0);
    for (int i = 0; i < kLanes; ++i) {
      const Sampler s(11, p, i + 1, 0, 0);
      rays.origin[i] =
          centre + Vec3{s.get(0) - 0.5f, s.get(1) - 0.5f, s.get(2) - 0.5f} * (2.0f * radius);
      const float z = 2 * s.get(3) - 1, r = std::sqrt(std::max(0.0f, 1 - z * z));
      const float phi = 2 * kPi * s.get(4);
      rays.direction[i] = {r * std::cos(phi), r * std::sin(phi), z};
    }
    setMask(rays, p % 3, random);
    const std::string diff = compareLanes(scene, rays, hitLanes);
    ASSERT_EQ(diff, "") << "incoherent packet " << p;
  }
  // Not vacuous: a good share of the lanes hit geometry.
  EXPECT_GT(hitLanes, packets * kLanes / 4);
}

// Every kind of primitive the Scene builds, placed every way it places them: a triangle mesh
// moved to world space (placed once, rotated and mirrored), a mesh instanced twice, spheres
// moved to world space (placed as they are) and instanced spheres (placed twice, scaled), and an
// emissive quad. The grid mesh is fine enough that many rays pass near shared edges.
SceneDesc everyPrimitive() {
  SceneDesc d;
  d.materials = {{"grey", MaterialType::Diffuse, Vec3{0.5f}, {}, 0, 1.5f},
                 {"light", MaterialType::Emissive, Vec3{0.0f}, Vec3{4.0f}, 0, 1.5f},
                 {"glass", MaterialType::Glass, Vec3{1.0f}, {}, 0, 1.5f}};
  Shape grid;
  grid.name = "grid";
  const int n = 48;
  for (int z = 0; z <= n; ++z)
    for (int x = 0; x <= n; ++x) {
      const float fx = float(x) / n * 4 - 2, fz = float(z) / n * 4 - 2;
      grid.mesh.positions.push_back({fx, 0.2f * std::sin(3 * fx) * std::cos(2 * fz), fz});
    }
  for (std::uint32_t z = 0; z < n; ++z)
    for (std::uint32_t x = 0; x < n; ++x) {
      const std::uint32_t a = z * (n + 1) + x, b = a + 1, c = a + n + 1, e = c + 1;
      grid.mesh.triangles.push_back({a, c, b});
      grid.mesh.triangles.push_back({b, c, e});
    }
  Shape box;
  box.name = "tetra";
  box.mesh = {{{0, 0, 0}, {0.6f, 0, 0}, {0, 0.6f, 0}, {0, 0, 0.6f}},
              {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}};
  Shape balls;
  balls.name = "balls";
  balls.spheres = {{{-1, 0.5f, -1}, {1, 0.4f, 1}, {0.5f, 0.3f, -0.8f}}, {0.3f, 0.25f, 0.2f}};
  Shape shared;
  shared.name = "shared balls";
  shared.spheres = {{{0, 0, 0}, {0.5f, 0, 0}}, {0.2f, 0.15f}};
  Shape lamp;
  lamp.name = "lamp";
  lamp.mesh = {{{-0.5f, 2, -0.5f}, {0.5f, 2, -0.5f}, {0.5f, 2, 0.5f}, {-0.5f, 2, 0.5f}},
               {{0, 1, 2}, {0, 2, 3}}};
  d.shapes = {grid, box, balls, shared, lamp};
  Affine mirrored = rotation({0, 1, 0}, 17.0f) * scaling({-1, 1, 1});
  mirrored.p = {0.1f, -0.3f, 0.2f};
  d.instances = {{0, mirrored, 0},
                 {1, translation({-0.8f, 0.3f, 0.4f}), 0},
                 {1, translation({0.7f, 0.2f, -0.3f}) * rotation({1, 1, 0}, 40.0f), 2},
                 {2, {}, 2},
                 {3, translation({0.2f, 0.8f, 0.1f}) * scaling(Vec3{1.5f}), 0},
                 {3, translation({-0.4f, 0.9f, -0.6f}), 0},
                 {4, {}, 1}};
  d.camera = {{0.3f, 2.5f, -4.0f}, {0, 0.2f, 0}, {0, 1, 0}, 50.0f, 0, 0};
  return d;
}

// The same scene without its spheres: what Embree's triangle packet kernels trace.
SceneDesc trianglesOnly() {
  SceneDesc d = everyPrimitive();
  std::erase_if(d.instances, [&](const Instance& i) { return d.shapes[i.shape].isSpheres(); });
  return d;
}

TEST(Packet, EveryLaneEqualsItsSingleRayOnFlattenedAndInstancedTriangles) {
  const Scene scene(trianglesOnly());
  ASSERT_TRUE(scene.tracesPackets());
  checkScene(scene, scene.desc().camera, 64, 48, {0, 0.5f, 0}, 2.5f);
}

// Embree's sphere packet kernel rounds t differently from its single-ray kernel (about a fifth
// of sphere hits differed in the last bits when measured), so scenes with spheres trace the
// packet's lanes one by one; the lanes must still equal single rays, triangles included.
TEST(Packet, EveryLaneEqualsItsSingleRayWithSpheresToo) {
  const Scene scene(everyPrimitive());
  EXPECT_FALSE(scene.tracesPackets());
  checkScene(scene, scene.desc().camera, 64, 48, {0, 0.5f, 0}, 2.5f);
  const Scene spheres(manySpheres(20, 16));
  checkScene(spheres, spheres.desc().camera, 48, 32, {0, 1, 0}, 10);
}

TEST(Packet, EveryLaneEqualsItsSingleRayInTheCornellBox) {
  const Scene scene(cornellBox());
  ASSERT_TRUE(scene.tracesPackets());
  checkScene(scene, scene.desc().camera, 48, 48, {278, 274, 280}, 280);
}

// The benchmark's bunny (75 k triangles), from libcgal-demo (scripts/setup installs it).
TEST(Packet, EveryLaneEqualsItsSingleRayOnTheStanfordBunny) {
  const std::string bunny = test::cgalBunny();
  ASSERT_FALSE(bunny.empty()) << "libcgal-demo is not installed (scripts/setup installs it)";
  SceneDesc d;
  d.materials = {{"white", MaterialType::Diffuse, Vec3{0.8f}, {}, 0, 1.5f}};
  Shape s;
  s.name = "bunny";
  s.mesh = importMesh(bunny);
  d.shapes = {s};
  d.instances = {{0, {}, 0}};
  d.camera = {{0, 0.2f, -2.2f}, {0, 0, 0}, {0, 1, 0}, 35.0f, 0, 0};
  const Scene scene(d);
  ASSERT_TRUE(scene.tracesPackets());
  checkScene(scene, d.camera, 160, 160, {0, 0, 0}, 0.2f);
}

// Rays aimed exactly at the grid's vertices and edge midpoints, where two or more triangles
// tie for the closest hit: the packet must break the tie as the single ray does.
TEST(Packet, TiesOnSharedEdgesBreakAsForSingleRays) {
  const SceneDesc d = trianglesOnly();
  const Scene scene(d);
  ASSERT_TRUE(scene.tracesPackets());
  const Affine& place = d.instances[0].transform;
  const auto& mesh = d.shapes[0].mesh;
  RayPacket rays;
  std::fill(std::begin(rays.active), std::end(rays.active), true);
  int hitLanes = 0, lane = 0;
  auto add = [&](Vec3 eye, Vec3 target) {
    rays.origin[lane] = eye;
    rays.direction[lane] = normalize(target - eye);
    if (++lane == kLanes) {
      lane = 0;
      const std::string diff = compareLanes(scene, rays, hitLanes);
      ASSERT_EQ(diff, "");
    }
  };
  for (const Vec3 eye : {Vec3{0.3f, 3.0f, -2.5f}, Vec3{-1.0f, 1.5f, 0.5f}})
    for (const auto& t : mesh.triangles) {
      const Vec3 a = place.point(mesh.positions[t[0]]), b = place.point(mesh.positions[t[1]]);
      add(eye, a);
      add(eye, (a + b) * 0.5f);
    }
  EXPECT_GT(hitLanes, static_cast<int>(mesh.triangles.size()));
}

// Camera rays set up several at a time (Camera::pinholeRays, SSE lanes) are the rays one at a
// time, bit for bit: the brick driver's plan traces single rays and its tiles the batches, and
// both must see the same bricks. Canvas points over and beyond the canvas, odd counts (a tail
// after the last whole group), and cameras turned so that no component is special.
TEST(Packet, PinholeRaysEqualSingleRays) {
  for (float degrees : {0.0f, 17.0f, 133.0f, 271.5f}) {
    const CameraDesc desc =
        orbitCamera({{0.3f, 1.7f, 6.1f}, {0.1f, -0.2f, 0}, {0, 1, 0}, 33.0f, 0, 0}, degrees);
    const Camera camera(desc, 1920, 1080);
    ASSERT_TRUE(camera.pinhole());
    for (std::size_t n : {std::size_t{1}, std::size_t{7}, std::size_t{1021}}) {
      std::vector<float> px(n), py(n);
      for (std::size_t i = 0; i < n; ++i) {
        const Sampler s(5, static_cast<int>(i), 3, 1, 0);
        px[i] = -40.0f + 2000.0f * s.get(0);
        py[i] = -40.0f + 1160.0f * s.get(1);
      }
      std::vector<Vec3> dirs(n), inv(n);
      camera.pinholeRays(n, px.data(), py.data(), dirs.data(), inv.data());
      for (std::size_t i = 0; i < n; ++i) {
        Vec3 origin, dir;
        camera.ray(px[i], py[i], 0.5f, 0.5f, origin, dir);
        ASSERT_TRUE(same(origin, camera.position()));
        ASSERT_TRUE(same(dir, dirs[i])) << "ray " << i << " of " << n << ", " << degrees << " deg";
        ASSERT_TRUE(same(Vec3{1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z}, inv[i])) << "ray " << i;
      }
    }
  }
}

}  // namespace
}  // namespace renderers
