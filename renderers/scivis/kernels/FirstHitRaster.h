#pragma once
// Camera rays' first hits on triangles by rasterising them, per frame, instead of asking Embree
// ray by ray: at wall resolutions a BVH walk per pixel (~100 ns a ray here) costs far more than
// visiting each triangle once over the few pixels it covers, as ParaView's rasteriser does.
//
// It finds exactly what a ray test finds, not an approximation of it: each pixel's own ray (its
// jittered sample, its clip interval) is tested against each triangle whose screen box holds the
// pixel, with a test made watertight by construction. All camera rays of a pinhole start at one
// point O, so a ray d meets triangle ABC when the three edge values
//   e0 = d . ((B-O) x (C-O)),  e1 = d . ((C-O) x (A-O)),  e2 = d . ((A-O) x (B-O))
// share a sign; two triangles sharing an edge compute that edge's value from the same two
// vertices in opposite order, which gives exactly the negated number (products commute, a - b =
// -(b - a), no fused multiply-adds in this file), so a ray through a shared edge is never let
// through, and one exactly on it sees both (the nearer, then the lower id, wins). The distance is
// t = n . (A-O) / n . d with the plane's normal n = (B-A) x (C-A) (not the triple product of the
// long vectors from the camera, which cancels badly), and the barycentric coordinates of B and C
// are e1 / (e0 + e1 + e2) and e2 / (e0 + e1 + e2) (Embree's u and v).
//
// Most triangles of a contour lie behind nearer ones, so a cell lists its triangles nearest
// first (sorted into buckets by their least depth along the camera's axis, a vertex's), a 4 x 4
// pixel block skips a triangle that lies wholly deeper than every hit its rays already hold, and
// a cell stops once its rays' hits all lie nearer than the next bucket. A triangle's record
// (edge planes, plane) is made only where a query reaches it (about a quarter of the listed
// ones at 2048^2 on the wavelet's contours). A hit shallower than its triangle's least depth
// (only rounding in a ray grazing the plane makes one) is no hit, so the bound holds for every
// hit found and the skipping never changes an answer.
//
// The result depends only on each ray and each triangle, not on binning, order, threads or which
// triangles a brick holds beside it: a brick and the whole scene find the same hit for a ray.
//
// Contracts: prepare() once per frame (not thread-safe), then firstHits() from any thread.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "renderers/Camera.h"

namespace renderers::scivis {

class FirstHitRaster {
 public:
  // A triangle mesh as the raster reads it (the caller keeps it alive): xyz per vertex, three
  // vertex indices (each below vertexCount: checked by whoever built the mesh) per triangle. `id`
  // is what hits report as the mesh (Embree's geometry ID).
  struct Mesh {
    const float* vertices = nullptr;
    std::size_t vertexCount = 0;
    const std::uint32_t* triangles = nullptr;
    std::size_t triangleCount = 0;
    std::uint32_t id = 0;
  };
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  struct Hit {
    float t = 0, u = 0, v = 0;
    std::uint32_t mesh = kNone, triangle = 0;  // mesh kNone: no hit
  };

  // Bins the triangles' clusters by the screen cells they cover, for `camera` on a width x
  // height canvas. False (and nothing binned) when rasterising cannot stand in for ray tests: a
  // camera with a lens, or a vertex not in front of the camera. `simd`: AVX-512 where the CPU
  // has it (false: the scalar kernel; both give the same bits). The clusters (and their copies
  // of the vertices) are made again only when a mesh's pointers or counts differ from the last
  // call's: meshes whose contents change in place need a new FirstHitRaster.
  bool prepare(const Camera& camera, int width, int height, const std::vector<Mesh>& meshes,
               bool simd = true);
  bool ready() const { return ready_; }
  void clear();

  // The first hit of the rays of pixels x0 .. x1 - 1 of rows y0 .. y1 - 1, one ray per pixel
  // (row-major, `stride` rays a row): the camera ray through a point of the pixel (the pixel's
  // own jitter) with unit direction (dx, dy, dz)[i], hits accepted at t0[i] <= t <= t1[i] (t1 <
  // t0: an inactive ray). out[i] as the ray test would answer.
  void firstHits(int x0, int x1, int y0, int y1, std::size_t stride, const float* dx,
                 const float* dy, const float* dz, const float* t0, const float* t1,
                 Hit* out) const;

  static constexpr int kCell = 16;  // screen cells are kCell x kCell pixels

  // A triangle this frame as the queries' kernels read it: its edge planes through the camera
  // (c0 opposite its first vertex, c1, c2), its plane's normal n, n . (A - O), and a depth along
  // the camera's axis no point of it lies nearer than.
  struct Setup {
    float c0[3], c1[3], c2[3], n[3];
    float det, near;
  };

 private:
  struct Vertex2 {
    float x, y, depth;
  };
  struct ScreenBox {
    std::int16_t x0, y0, x1, y1;  // the pixels a triangle may cover (inclusive)
  };
  // A run of triangles near one another in space (in clustered_) and their box: what the
  // raster bins, made once for a set of meshes.
  struct Cluster {
    std::uint32_t first, count, mesh;  // its triangles: clustered_[first .. first + count - 1]
    std::uint32_t points, pointCount;  // its vertices' copies in clusterPoints_
  };
  struct Placed {                        // a cluster this frame
    std::uint32_t first, points, count;  // as its Cluster's
    float near;  // no triangle of the cluster lies at a lesser depth (below its Setup::near)
    ScreenBox box;
  };
  int bucketOf(float depth) const;
  std::size_t meshOf(std::size_t triangle) const;  // global index to mesh
  bool sameMeshes(const std::vector<Mesh>& meshes) const;
  void makeClusters(const std::vector<Mesh>& meshes, std::size_t total);
  Setup setupOf(const float* a, const float* b, const float* c, float near) const;
  bool ready_ = false;
  int width_ = 0, height_ = 0, cellsX_ = 0, cellsY_ = 0;
  float originX_ = 0, originY_ = 0, originZ_ = 0;
  float forwardX_ = 0, forwardY_ = 0, forwardZ_ = 0;
  std::vector<Mesh> meshes_;
  std::vector<std::size_t> firstTriangle_;    // per mesh: its first global triangle index
  std::vector<Mesh> clusteredMeshes_;         // what clusters_ were made of
  std::vector<std::uint32_t> clustered_;      // global triangle indices, cluster by cluster
  std::vector<std::uint8_t> clusterCorners_;  // their vertices (3 each) in their cluster's points
  std::vector<float> clusterPoints_;          // xyz per point, cluster by cluster
  std::vector<Cluster> clusters_;
  std::vector<Vertex2> clusterScreen_;      // per point: canvas position, depth
  std::vector<Placed> placed_;              // per cluster, this frame
  std::vector<Placed> order_;               // the binned clusters, nearest bucket first
  std::vector<std::uint32_t> cellStart_;    // per cell + 1: offsets into cellClusters_
  std::vector<Placed> cellClusters_;        // per cell, in order_'s order
  std::vector<std::uint32_t> counts_;       // per chunk and bucket or cell: counts, offsets
  float bucketFrom_ = 0, bucketScale_ = 0;  // bucketOf()'s mapping of depths
  bool simd_ = false;
};

}  // namespace renderers::scivis
