#include "api/SceneStyle.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "base/Collectives.h"
#include "renderers/TransferFunction.h"
#include "renderers/scivis/io/SciVisDesc.h"

namespace dfbwall {
namespace {

renderers::Vec3 vec(const Vec3f& v) { return {v[0], v[1], v[2]}; }

renderers::GridGeometry geometry(const FieldGrid& g) {
  renderers::GridGeometry out;
  out.dims = {g.dims[0], g.dims[1], g.dims[2]};
  out.origin = vec(g.origin);
  out.spacing = vec(g.spacing);
  return out;
}

// What the renderer holds a voxel type as: the types it samples as they are, the others float32.
renderers::VoxelType voxelType(VoxelType t) {
  switch (t) {
    case VoxelType::UInt8:
      return renderers::VoxelType::UInt8;
    case VoxelType::UInt16:
      return renderers::VoxelType::UInt16;
    default:
      break;
  }
  return renderers::VoxelType::Float32;
}

// `count` voxels of type `t` at `from` into what voxelType(t) holds, at `to`.
void convertVoxels(VoxelType t, const void* from, std::byte* to, std::size_t count) {
  auto each = [&](auto sample) {
    using T = decltype(sample);
    for (std::size_t n = 0; n < count; ++n) {
      T v;
      std::memcpy(&v, static_cast<const std::byte*>(from) + n * sizeof(T), sizeof v);
      const float f = static_cast<float>(v);
      std::memcpy(to + n * sizeof f, &f, sizeof f);
    }
  };
  switch (t) {
    case VoxelType::Int8:
      return each(std::int8_t{});
    case VoxelType::Int16:
      return each(std::int16_t{});
    case VoxelType::Int32:
      return each(std::int32_t{});
    case VoxelType::Float64:
      return each(double{});
    default:  // held as given
      std::memcpy(to, from, count * renderers::voxelBytes(voxelType(t)));
  }
}

[[noreturn]] void fail(const Brick& brick, const std::string& what) {
  throw std::runtime_error("dfbwall: brick " + std::to_string(brick.id) + ": " + what);
}

// The program's voxels read where they are, its owner (if any) held with them. Their value range
// is taken when the scene version that uses them is made (Session::Impl::commit), not here: the
// program may still change them until that frame.
void borrow(const Brick& brick, const std::string& name, const VolumePart& part,
            renderers::Volume& volume) {
  if (part.type != VoxelType::Float32 && part.type != VoxelType::UInt8 &&
      part.type != VoxelType::UInt16)
    fail(brick, name +
                    ": borrowed voxels must be float32, uint8 or uint16 (the others are "
                    "converted to float32, so they are copied: give them without borrowed)");
  const std::size_t width = renderers::voxelBytes(volume.type);
  if (reinterpret_cast<std::uintptr_t>(part.voxels) % width != 0)
    fail(brick, name + ": borrowed voxels must be aligned to their size (" + std::to_string(width) +
                    " bytes)");
  volume.borrowed =
      std::shared_ptr<const std::byte>(part.owner, static_cast<const std::byte*>(part.voxels));
  volume.borrowedBytes = volume.box.voxelCount() * width;
}

renderers::scivis::ParticlesDesc particles(const Brick& brick, const Particles& p,
                                           const char* field) {
  if (!(p.radii.size() == 1 || p.radii.size() == p.centers.size()) && !p.centers.empty())
    fail(brick, std::string(field) + ".radii has " + std::to_string(p.radii.size()) +
                    " entries: give 1 or one per centre (" + std::to_string(p.centers.size()) +
                    ")");
  renderers::scivis::ParticlesDesc out;
  out.name = field;
  out.material = 0;
  for (const Vec3f& c : p.centers) out.centers.push_back(vec(c));
  out.radii = p.radii;
  return out;
}

renderers::scivis::WorldMesh mesh(const Brick& brick, const Mesh& m, const char* field) {
  renderers::scivis::WorldMesh out;
  out.material = 1;
  for (const Vec3f& v : m.positions) out.mesh.positions.push_back(vec(v));
  for (const auto& t : m.triangles) {
    for (std::uint32_t i : t)
      if (i >= m.positions.size())
        fail(brick, std::string(field) + ": a triangle refers to vertex " + std::to_string(i) +
                        " of " + std::to_string(m.positions.size()));
    out.mesh.triangles.push_back(t);
  }
  return out;
}

// The canonical serialisation styleHash() hashes, fed byte by byte.
class Fnv1a {
 public:
  void bytes(const void* data, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) hash_ = (hash_ ^ b[i]) * 0x100000001b3ull;
  }
  void u64(std::uint64_t v) {
    unsigned char b[8];
    for (int i = 0; i < 8; ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
    bytes(b, 8);
  }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f32(float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    u64(bits);
  }
  void vec(const Vec3f& v) {
    for (float c : v) f32(c);
  }
  void text(const std::string& s) {
    u64(s.size());
    bytes(s.data(), s.size());
  }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 0xcbf29ce484222325ull;
};

}  // namespace

// A field added to Style or to a struct it holds must be hashed below: these sizes change with
// it (on the platform the suite runs on) and remind whoever adds one.
#if defined(__x86_64__) && defined(__GLIBCXX__)
static_assert(sizeof(FieldGrid) == 36 && sizeof(VolumeStyle) == 128 && sizeof(Isosurface) == 24 &&
                  sizeof(Light) == 44 && sizeof(Style) == 144,
              "a field was added to dfbwall::Style: hash it in styleHash()");
#endif

std::uint64_t styleHash(const Style& style) {
  Fnv1a h;
  h.u64(style.volumes.size());
  for (const VolumeStyle& v : style.volumes) {
    h.text(v.name);
    for (int d : v.grid.dims) h.i64(d);
    h.vec(v.grid.origin);
    h.vec(v.grid.spacing);
    h.text(v.transferFunction);
    h.f32(v.maxOpacity);
    h.u64(v.autoRange ? 1 : 0);
    h.f32(v.valueMin);
    h.f32(v.valueMax);
    h.u64(v.visible ? 1 : 0);
  }
  h.u64(style.isosurfaces.size());
  for (const Isosurface& i : style.isosurfaces) {
    h.i64(i.volume);
    h.f32(i.value);
    h.vec(i.color);
    h.f32(i.opacity);
  }
  h.vec(style.particleColor);
  h.f32(style.particleOpacity);
  h.vec(style.meshColor);
  h.f32(style.meshOpacity);
  h.u64(style.lights.size());
  for (const Light& l : style.lights) {
    h.i64(static_cast<std::int64_t>(l.kind));
    h.vec(l.direction);
    h.vec(l.position);
    h.vec(l.color);
    h.f32(l.intensity);
  }
  h.i64(style.aoSamples);
  h.f32(style.aoDistance);
  h.u64(style.shadows ? 1 : 0);
  h.f32(style.samplingRate);
  h.vec(style.background);
  h.i64(style.samplesPerPixel);
  h.u64(style.seed);
  return h.value();
}

renderers::scivis::BrickContent brickContent(const Style& style, const Brick& brick) {
  if (brick.id < 0) fail(brick, "the id must not be negative");
  renderers::scivis::BrickContent c;
  c.bounds = {vec(brick.boundsLo), vec(brick.boundsHi)};
  if (!brick.volumes.empty() && brick.volumes.size() != style.volumes.size())
    fail(brick, "volumes has " + std::to_string(brick.volumes.size()) + " entries; the style has " +
                    std::to_string(style.volumes.size()) +
                    " volumes (give one part each, or none)");
  for (std::size_t v = 0; v < style.volumes.size(); ++v) {
    renderers::Volume volume;
    volume.grid = geometry(style.volumes[v].grid);
    const VolumePart* part = brick.volumes.empty() ? nullptr : &brick.volumes[v];
    if (part) volume.type = voxelType(part->type);
    if (part && part->lo != part->hi) {
      renderers::VoxelBox box{{part->lo[0], part->lo[1], part->lo[2]},
                              {part->hi[0], part->hi[1], part->hi[2]}};
      const std::string name = "volume '" + style.volumes[v].name + "'";
      if (box.empty() || !volume.grid.wholeBox().contains(box))
        fail(brick, name + ": the voxel box is empty or outside the field's dims");
      for (int a = 0; a < 3; ++a)
        if (box.hi[a] - box.lo[a] < 2) fail(brick, name + ": the voxel box is under 2 voxels wide");
      if (!part->voxels) fail(brick, name + ": voxels is null");
      volume.box = box;
      if (part->borrowed) {
        borrow(brick, name, *part, volume);
      } else {
        volume.voxels = renderers::allocateVoxelBytes(box, volume.type);
        convertVoxels(part->type, part->voxels, volume.voxels.data(), box.voxelCount());
        volume.updateRange();
      }
    }
    c.volumes.push_back(std::move(volume));
  }
  if (!brick.particles.centers.empty())
    c.particles.push_back(particles(brick, brick.particles, "particles"));
  if (!brick.ghostParticles.centers.empty())
    c.ghostParticles.push_back(particles(brick, brick.ghostParticles, "ghostParticles"));
  if (!brick.mesh.triangles.empty()) c.meshes.push_back(mesh(brick, brick.mesh, "mesh"));
  if (!brick.ghostMesh.triangles.empty())
    c.ghostMeshes.push_back(mesh(brick, brick.ghostMesh, "ghostMesh"));
  return c;
}

renderers::SceneDesc sceneDesc(const Style& style,
                               const std::vector<renderers::scivis::HeldBrick>& mine,
                               MPI_Comm renderComm, std::chrono::milliseconds timeout) {
  renderers::SceneDesc d;
  renderers::scivis::SciVisDesc& scivis = renderers::scivis::sciVisDesc(d);
  renderers::Material particle, surface;
  particle.name = "particles";
  particle.color = vec(style.particleColor);
  particle.opacity = style.particleOpacity;
  particle.specular = 0.25f;
  surface.name = "meshes";
  surface.color = vec(style.meshColor);
  surface.opacity = style.meshOpacity;
  d.materials = {particle, surface};

  // The value ranges every rank colours by: min of -max and of min in one reduction.
  const std::size_t n = style.volumes.size();
  std::vector<float> local(2 * n, -std::numeric_limits<float>::max()), global(2 * n);
  for (const renderers::scivis::HeldBrick& b : mine)
    for (std::size_t v = 0; v < n && v < b.content.volumes.size(); ++v) {
      const renderers::Volume& vol = b.content.volumes[v];
      if (vol.dataBytes() == 0) continue;
      local[2 * v] = std::max(local[2 * v], -vol.valueMin);
      local[2 * v + 1] = std::max(local[2 * v + 1], vol.valueMax);
    }
  const bool anyAuto = std::any_of(style.volumes.begin(), style.volumes.end(),
                                   [](const VolumeStyle& v) { return v.autoRange; });
  if (anyAuto && n > 0)
    base::allreduce(local.data(), global.data(), static_cast<int>(2 * n), MPI_FLOAT, MPI_MAX,
                    renderComm,
                    {.until = timeout,
                     .late = "value ranges of a new scene version: another render rank did not "
                             "join in time"});
  for (std::size_t v = 0; v < n; ++v) {
    const VolumeStyle& s = style.volumes[v];
    float lo = s.valueMin, hi = s.valueMax;
    if (s.autoRange) {
      lo = -global[2 * v], hi = global[2 * v + 1];
      if (!(hi > lo)) hi = lo + 1;  // a constant field (or none anywhere): any non-empty range
    }
    renderers::scivis::VolumeDesc vd;
    vd.name = s.name;
    vd.source.grid = geometry(s.grid);
    vd.transfer = renderers::transferFunctionPreset(s.transferFunction, lo, hi, s.maxOpacity);
    vd.visible = s.visible;
    scivis.volumes.push_back(std::move(vd));
  }
  for (const Isosurface& iso : style.isosurfaces) {
    if (iso.volume < 0 || static_cast<std::size_t>(iso.volume) >= n)
      throw std::runtime_error("dfbwall: an isosurface refers to volume " +
                               std::to_string(iso.volume) + " of " + std::to_string(n));
    renderers::Material m;
    m.name = "isosurface" + std::to_string(scivis.isosurfaces.size());
    m.color = vec(iso.color);
    m.opacity = iso.opacity;
    m.specular = 0.3f;
    scivis.isosurfaces.push_back({static_cast<std::uint32_t>(iso.volume), iso.value,
                                  static_cast<std::uint32_t>(d.materials.size())});
    d.materials.push_back(m);
  }
  for (const Light& l : style.lights) {
    renderers::scivis::LightDesc ld;
    ld.kind = l.kind == Light::Kind::Point     ? renderers::scivis::LightDesc::Kind::Point
              : l.kind == Light::Kind::Ambient ? renderers::scivis::LightDesc::Kind::Ambient
                                               : renderers::scivis::LightDesc::Kind::Directional;
    ld.direction = vec(l.direction);
    ld.position = vec(l.position);
    ld.color = vec(l.color);
    ld.intensity = l.intensity;
    scivis.lights.push_back(ld);
  }
  d.environment.color = vec(style.background);
  if (style.aoSamples > 0 && !(style.aoDistance > 0))
    throw std::runtime_error(
        "dfbwall: Style.aoDistance must be positive with aoSamples (a brick cannot know the "
        "whole scene's extent)");
  scivis.settings.aoSamples = style.aoSamples;
  scivis.settings.aoDistance = style.aoDistance;
  scivis.settings.shadows = style.shadows;
  scivis.settings.samplingRate = style.samplingRate;
  return d;
}

}  // namespace dfbwall
