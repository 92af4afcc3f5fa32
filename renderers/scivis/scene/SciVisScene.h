#pragma once
// What the scivis renderer traces: one brick of a scene (the whole scene is the one brick with
// unbounded clip bounds). Camera rays see the brick's volumes, isosurfaces, particles and meshes
// inside `bounds`; shading rays (shadows, ambient occlusion) also see the ghost data around it
// (ghost voxels of its volumes, ghost particles and meshes), so a brick shades its points
// exactly as the whole scene does when its ghosts hold what those rays can reach.
//
// Contracts: construction builds everything (Embree BVHs, macrocells) and throws
// base::Error on invalid input; afterwards every const method is thread-safe.
#include <cstdint>
#include <memory>
#include <vector>

#include "renderers/RendererScene.h"
#include "renderers/SceneDesc.h"
#include "renderers/Volume.h"
#include "renderers/scivis/io/SciVisDesc.h"
#include "renderers/scivis/kernels/FirstHitRaster.h"
#include "renderers/scivis/scene/Box.h"
#include "renderers/scivis/scene/ShadingShell.h"
#include "renderers/scivis/scene/VolumeField.h"

namespace renderers::scivis {

// Triangles in world space with one material: a scene's mesh instance, or the part of one a
// brick holds.
struct WorldMesh {
  TriangleMesh mesh;
  std::uint32_t material = 0;
};

struct BrickContent {
  Box3 bounds;  // camera rays are clipped to it
  // One entry per SciVisDesc::volumes, holding the voxels this brick has of it (an empty box:
  // none). Voxels beyond `bounds` are ghost layers: shading rays and gradients see them.
  std::vector<Volume> volumes;
  // Per volume (or none at all): the sparse ghost shell shading rays test isosurfaces in, when
  // it reaches beyond `volumes` (--ghost reach); an empty one: shading rays use `volumes`.
  std::vector<ShadingShell> shells;
  std::vector<ParticlesDesc> particles, ghostParticles;
  std::vector<WorldMesh> meshes, ghostMeshes;

  std::size_t bytes() const;  // the data held: voxels, particles, triangles
};

// The scene's mesh instances (and sphere shapes, as particles) moved to world space.
std::vector<WorldMesh> worldMeshes(const SceneDesc& desc);
// Every particle set of the scene: its [[particles]] and the path tracer's sphere shapes (made
// into particle sets in `converted`, which must outlive the pointers).
std::vector<const ParticlesDesc*> particleSets(const SceneDesc& desc,
                                               std::vector<ParticlesDesc>& converted);
// The bounds of everything in the scene (volumes' voxel centres, particles, meshes).
Box3 sceneDomain(const SceneDesc& desc);

// A surface found by a ray: where, its shading normal (unit, any side) and what it looks like.
struct SurfaceHit {
  float t = 0;
  Vec3 normal;
  Vec3 color;
  const Material* material = nullptr;
};

struct ResolvedLight {
  LightDesc::Kind kind;
  Vec3 direction;  // directional: towards the light (unit)
  Vec3 position;
  Vec3 radiance;  // color * intensity
};

// The scene's lights as the renderer uses them: as given, or (none given) an ambient light and
// a directional one from the scene camera's position (the description's camera, fixed: it does
// not follow the camera of a frame).
std::vector<ResolvedLight> resolveLights(const SceneDesc& desc);

class SciVisScene final : public RendererScene {
 public:
  SciVisScene(std::shared_ptr<const SceneDesc> desc, BrickContent content);
  ~SciVisScene();
  SciVisScene(const SciVisScene&) = delete;
  SciVisScene& operator=(const SciVisScene&) = delete;

  const SceneDesc& desc() const { return *desc_; }
  const SciVisDesc& sciVis() const { return *sciVis_; }  // desc()'s scivis parts
  const Box3& bounds() const { return content_.bounds; }
  const BrickContent& content() const { return content_; }
  // Moves the data out, for a new scene version that keeps it; destroy the scene next.
  BrickContent release() { return std::move(content_); }
  // What the scene holds: content().bytes() and what Embree holds (surfaces, isosurface
  // triangles and their BVHs).
  std::size_t bytes() const;

  // The isosurfaces as triangles, made at construction: triangles camera rays can hit, those
  // only shading rays see (ghost cells), and the seconds polygonising and building BVHs took.
  struct IsosurfaceStats {
    std::size_t cameraTriangles = 0, shadingTriangles = 0;
    double seconds = 0;
  };
  const IsosurfaceStats& isosurfaceStats() const { return isosurfaceStats_; }

  // The closest surface (mesh, particle or isosurface) along origin + t dir with t in
  // [tNear, tFar], camera data only.
  bool intersectSurface(Vec3 origin, Vec3 dir, float tNear, float tFar, SurfaceHit& hit) const;
  // intersectSurface() for up to kSurfacePacket rays at once, the same hits bit for bit:
  // found[i] = intersectSurface(queries[i]..., hits[i]) for the active queries. Traced as one
  // Embree packet when the camera data are triangles only (the packet and single-ray triangle
  // tests agree exactly, as renderers/Scene's packets rely on; sphere tests do not), else one
  // ray at a time.
  struct SurfaceQuery {
    Vec3 origin, dir;
    float tNear, tFar;
    bool active;
  };
  static constexpr int kSurfacePacket = 16;
  // Whether camera rays can meet any surface at all (else intersectSurface() finds none).
  bool hasCameraSurfaces() const;
  void intersectSurfaces(const SurfaceQuery* queries, int count, SurfaceHit* hits,
                         bool* found) const;
  // The camera data as triangle meshes for FirstHitRaster (ids: the geometry IDs of hits), when
  // they are all camera rays can meet (no spheres) and every one is opaque, so that a camera ray
  // ends at its first surface and nothing behind it is asked for. Otherwise false.
  bool opaqueCameraTriangles(std::vector<FirstHitRaster::Mesh>& out) const;
  // A hit's shading data from its geometry ID, primitive, barycentric coordinates (of vertices
  // 1 and 2) and distance along origin + t dir.
  void fillSurfaceHit(std::uint32_t geomID, std::uint32_t prim, float u, float v, float t,
                      Vec3 origin, Vec3 dir, SurfaceHit& hit) const;
  // Whether any surface (camera or ghost data) blocks origin + t dir, t in [tNear, tFar].
  bool surfaceOccluded(Vec3 origin, Vec3 dir, float tNear, float tFar) const;

  struct VolumeLayer {
    const VolumeField* field = nullptr;   // null when this brick holds none of the volume
    const ShadingShell* shell = nullptr;  // what shading rays test instead of `field`, if set
    // kTableSize entries of 8 floats: RGBA (opacity per renderer step), then the next entry's
    // RGBA minus this one's (float subtraction; 0 in the last entry, which no lookup starts
    // from). A lookup is entry + weight x difference: the bits of entry + weight x (next -
    // entry), one subtraction shorter on the march's longest path.
    std::vector<float> table;
    std::vector<std::uint32_t> visibleUpTo;  // prefix counts of entries with opacity > 0
    float valueMin = 0, tableScale = 0;
    bool visible = true;
    // Found as triangles (Embree), not on the volume: they are surfaces to rays.
    std::vector<const IsosurfaceDesc*> isosurfaces;
    // Per macrocell of `field`: 1 when the transfer function shows nothing in its value range,
    // so rays may jump over it.
    std::vector<std::uint8_t> emptyMacrocells;
  };
  static constexpr int kTableSize = 4096;
  static constexpr int kTableEntryFloats = 8;  // RGBA and the difference to the next entry
  // The volumes one scene may hold: the renderer keeps each volume's samples along a ray in
  // arrays of this size. Scene files with more are refused when read (SciVisToml.cpp), other
  // descriptions when the scene is built.
  static constexpr std::size_t kMaxVolumes = 8;
  const std::vector<VolumeLayer>& volumes() const { return volumes_; }
  // The volume layers with another transfer function: preset `preset` (an index in
  // transferFunctionPresetNames(); -1: each volume's own) over each volume's value range and
  // with its peak opacity, every opacity times `opacityScale` (steering).
  std::vector<VolumeLayer> retunedVolumes(int preset, float opacityScale) const;
  float volumeStep() const { return step_; }  // world distance between volume samples
  // Whether the volume's transfer function shows anything (opacity) in [lo, hi].
  static bool anythingIn(const VolumeLayer& v, float lo, float hi);

  const std::vector<ResolvedLight>& lights() const { return lights_; }
  float aoDistance() const { return aoDistance_; }
  float extent() const { return extent_; }
  // The whole scene's domain (sceneDomain(): every brick's scene has the same).
  const Box3& domain() const { return domain_; }

 private:
  // Fills layer's table, visibility counts and empty macrocells for `tf` (opacities times
  // `opacityScale`) at this scene's step.
  void bake(VolumeLayer& layer, const VolumeDesc& vd, const TransferFunction& tf,
            float opacityScale) const;
  // Polygonises volume `volume`'s isosurfaces into the Embree scenes: the cells camera rays can
  // hit into both, the other dense cells and the shading shell's into the shading scene.
  void addIsosurfaces(std::size_t volume);

  std::shared_ptr<const SceneDesc> desc_;
  const SciVisDesc* sciVis_;  // in *desc_
  BrickContent content_;
  std::vector<std::unique_ptr<VolumeField>> fields_;
  std::vector<VolumeLayer> volumes_;
  std::vector<ResolvedLight> lights_;
  float step_ = 1, aoDistance_ = 1, extent_ = 1;
  Box3 domain_;
  IsosurfaceStats isosurfaceStats_;
  struct Embree;
  std::unique_ptr<Embree> embree_;
};

}  // namespace renderers::scivis
