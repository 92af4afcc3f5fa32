#pragma once
// dfbwall's data-distributed API (Usher et al., EuroVis 2019, section 5): for MPI programs that
// already own distributed data (a simulation, an analysis tool). Each render rank adds the
// bricks it holds — a sub-box of a volume in whole-field voxel coordinates, particles, triangles,
// each brick with the bounds camera rays are clipped to and any ghost data around them — and
// renders frames of them with the scivis renderer through the Distributed FrameBuffer: sort-last
// compositing per tile, on a display wall or into an image on render rank 0.
//
// Ranks. The program gives its communicator. Without a wall every rank renders. With a wall
// layout of W wall processes the LAST W ranks of the communicator drive the displays: on them
// isWallRank() is true and the program calls runWall(), which presents frames until the render
// ranks close the session, and does nothing else with them. The program simulates on
// renderComm() (the first size - W ranks).
//
// Scene versions. setStyle() and the bricks (addBrick / clearBricks) make a scene version; the
// next renderFrame() after any render rank changed either is the new version: the ranks then
// exchange their bricks' ids and bounds (one allgather) and, for volumes whose range is not
// given, the value range. Frames of one version with one camera accumulate (progressive
// refinement); a new version or camera starts the average afresh. The same brick id on several
// ranks must be the same data (replication: either rank may render it).
//
// Every call but the accessors is collective over the render ranks (renderFrame, close; setStyle,
// addBrick, clearBricks, dataChanged and setCamera are local and take effect at the next
// renderFrame). MPI must be initialised with MPI_THREAD_MULTIPLE (the messaging runs on its own
// thread).
//
// Errors are thrown, never turned into MPI_Abort by the library. Every wait is bounded by
// SessionOptions::timeoutSeconds: a rank that stops answering (or a program that takes longer
// between frames than that, with a wall waiting) is an error, thrown as std::runtime_error naming
// the cause. An error found on the session's messaging threads (a message for no object, one that
// does not decode, a handler that threw) is kept and thrown by this rank's renderFrame(),
// close() or runWall() in progress, or else its next one: "dfbwall: error on rank R (HOST):
// cause". renderFrame() shares it in its per-frame exchange, so the other render ranks throw
// ("render rank R failed") at the same frame; a rank waiting for a failed peer anywhere else
// throws at its deadline at the latest.
//
// Bad input is an InputError, thrown by the next renderFrame() on every render rank alike: a
// brick that does not fit the style (addBrick keeps the refusal instead of throwing on one rank
// only; the message names the render rank, the brick and the field) and different styles. A
// renderFrame() before setStyle() on some rank is a std::logic_error on every rank. These leave
// the ranks in step: give the corrected input again (setStyle; clearBricks and addBrick) and
// render again. After any other error the session is unusable (every further renderFrame()
// throws; close() on every rank still releases it): end the job with MPI_Abort.
//
// Leaving. close() is the one collective way out. The destructor never waits for another rank:
// a session destroyed without close() (a rank that returns early, an exception) tells the other
// ranks it left, and their renderFrame() or close() then throws "rank R (HOST) left without
// closing" at once instead of waiting until their deadline.
//
// Threads and floating point. Rendering runs in the session's own TBB task arena
// (SessionOptions::threads), joined by the thread that calls renderFrame(); its tasks run with
// flush-to-zero and denormals-are-zero on, whatever the caller's mode, so the image never depends
// on it. renderFrame() and runWall() give the calling thread its own mode (MXCSR FTZ/DAZ) back
// when they return or throw.
#include <mpi.h>

#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace dfbwall {

// Input the session refuses (a brick outside its field, a wrong voxel count, styles that differ
// between ranks, MPI_COMM_NULL): thrown alike on every render rank; the session stays usable.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

using Vec3f = std::array<float, 3>;
using Index3 = std::array<int, 3>;

// Float32, UInt8, UInt16 are held as given; Int8, Int16, Int32 and Float64 are converted to
// float32 when the brick is added (exact for int8, int16 and integers up to 2^24; float64 rounds
// to the nearest float32). Float voxels may be NaN for missing values: they render as empty
// space and are left out of the value range.
enum class VoxelType { Float32, UInt8, UInt16, Int8, Int16, Int32, Float64 };

// One volume's whole field: its grid and where it sits in the world. Voxel (i, j, k) is at
// origin + spacing * (i, j, k) (vertex-centred, as VTK image data).
struct FieldGrid {
  Index3 dims{2, 2, 2};
  Vec3f origin{0, 0, 0};
  Vec3f spacing{1, 1, 1};
};

// How a volume looks. The transfer function is a preset ("cool-warm", "viridis", "grayscale",
// "inferno", "rainbow") over [valueMin, valueMax] with opacity rising linearly from 0 to
// maxOpacity (per voxel spacing of world distance); autoRange takes the range of the voxels all
// ranks hold at each scene version instead.
struct VolumeStyle {
  std::string name = "volume";
  FieldGrid grid;
  std::string transferFunction = "cool-warm";
  float maxOpacity = 0.1f;
  bool autoRange = true;
  float valueMin = 0, valueMax = 1;
  bool visible = true;  // false: only its isosurfaces show
};

struct Isosurface {
  int volume = 0;  // index into Style::volumes
  float value = 0;
  Vec3f color{0.8f, 0.8f, 0.8f};
  float opacity = 1;
};

struct Light {
  enum class Kind { Directional, Point, Ambient };
  Kind kind = Kind::Directional;
  Vec3f direction{0, -1, 0};  // directional: the way the light travels
  Vec3f position{0, 0, 0};    // point
  Vec3f color{1, 1, 1};
  float intensity = 1;
};

// Everything but the data, the same on every render rank: at each scene version the ranks compare
// a hash of every field (floats by their bits), and ranks that passed different styles make
// renderFrame() throw on every rank, naming the lowest rank that differs from render rank 0.
struct Style {
  std::vector<VolumeStyle> volumes;
  std::vector<Isosurface> isosurfaces;
  Vec3f particleColor{0.9f, 0.6f, 0.2f};
  float particleOpacity = 1;
  Vec3f meshColor{0.7f, 0.7f, 0.7f};
  float meshOpacity = 1;
  std::vector<Light> lights;  // empty: an ambient light and a headlight
  int aoSamples = 0;          // ambient-occlusion rays per hit and sample
  float aoDistance = 0;       // how far they look (world units; > 0 when aoSamples > 0)
  bool shadows = false;       // shadow rays see only the brick and its ghost data
  float samplingRate = 1;     // volume samples per voxel spacing
  Vec3f background{0.1f, 0.1f, 0.12f};
  int samplesPerPixel = 1;  // per frame
  std::uint64_t seed = 0;
};

// A brick's part of one volume: the voxels [lo, hi) of the whole field (x fastest, then y, then
// z), copied by addBrick, or borrowed (below). Shading rays see exactly the voxels given, so the
// box is the program's choice of ghost data (dfbwall --ghost offers the same two): for seams that
// match the whole field exactly it covers the clip bounds plus 2 voxels below and 3 above on each
// axis (where the field has them) — one ghost layer, the least memory, but ambient occlusion near
// the brick's faces sees only the brick — and for AO that equals the whole field's, the AO
// distance beyond that too. lo == hi: this brick has none of the volume.
//
// Borrowed voxels (`borrowed`, float32, uint8 and uint16 only, aligned to their size) are read
// where they are: the session holds no copy (sceneBytes() leaves them out; borrowedBytes()
// counts them). The program keeps them alive and unchanged while the session holds the brick:
// from addBrick() until the renderFrame() that replaces its bricks (the first one after
// clearBricks() or a new addBrick() that commits; a frame that throws keeps the old ones), or
// close() or the destructor. It may change their values between frames (never while
// renderFrame() runs) and then calls dataChanged() before the next frame; a frame without it
// reads the new values through structures built from the old ones (value ranges, macrocells,
// isosurfaces): stale, never outside the box. `owner`, when given, is held as long as the
// session holds the voxels (the Python module keeps its numpy arrays alive this way). Other
// voxel types are converted when added, so borrowing them is refused (InputError).
struct VolumePart {
  Index3 lo{0, 0, 0}, hi{0, 0, 0};
  VoxelType type = VoxelType::Float32;
  const void* voxels = nullptr;
  bool borrowed = false;
  std::shared_ptr<const void> owner;
};

struct Particles {
  std::vector<Vec3f> centers;
  std::vector<float> radii;  // one for all, or one per particle
};

struct Mesh {
  std::vector<Vec3f> positions;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

struct Brick {
  int id = 0;                                  // >= 0; the same id on two ranks: the same data
  Vec3f boundsLo{0, 0, 0}, boundsHi{0, 0, 0};  // camera rays are clipped to these bounds
  std::vector<VolumePart> volumes;             // one per Style::volumes (or none: no volume data)
  Particles particles, ghostParticles;         // ghost: seen by shading rays only
  Mesh mesh, ghostMesh;
};

struct Camera {
  Vec3f position{0, 0, -5};
  Vec3f lookAt{0, 0, 0};
  Vec3f up{0, 1, 0};
  float fovY = 45;  // degrees
};

struct SessionOptions {
  int width = 800, height = 600;  // without a wall; with one the layout's canvas
  std::string wall;               // wall layout TOML (empty: no wall, image() on render rank 0)
  bool offscreen = true;          // OSMesa; false: GLFW windows
  std::string captureDir;         // wall captures DIR/<display>/frame-NNNNNN.png, DIR/wall-*.png
  int captureEvery = 0;           // every K-th frame; 0: the last one only
  int tileSize = 64;
  // Threads per render rank (0: all cores): the session renders in a TBB task arena of its own
  // with this many threads and combines tiles with as many; the program's own TBB parallelism
  // (its arenas, its tbb::global_control) is neither capped nor used by it.
  int threads = 0;
  int framesInFlight = 2;    // frames rendered ahead of the wall
  int timeoutSeconds = 300;  // bound of every wait (see above)
  float exposure = 1;        // tone mapping: linear radiance times this, then sRGB
  // A wall that `dfbwall serve` runs ("HOST:PORT"), instead of `wall`: every rank of the
  // communicator renders, and the pieces go straight from the tile owners to the wall's
  // processes (the wall is not part of this job). Render rank 0 reads the wall's layout from it;
  // captureDir is then a folder on the wall's hosts. The wall's token: `tokenFile`, else `token`
  // (for tests), else the environment variable DFBWALL_TOKEN, else the default token file
  // (~/.local/state/dfbwall/wall-token; docs/security.md); read by rank 0 only. `serverKeyFile`:
  // the wall's CURVE public key (serve --curve): the links are encrypted and a wall that does not
  // hold the key is refused. `codec`: "raw", "snappy" or "jpeg[:QUALITY]"; `wait`: queue behind
  // a job the wall is showing instead of failing with its "busy" error. `window`: the part of
  // the wall the session covers, as `dfbwall --window`: "X,Y,W,H" (wall canvas pixels, bezels
  // included), a display's name, or "full"/empty (the whole canvas); the session's canvas is the
  // window (docs/service.md, "A job in a window").
  std::string connect;
  std::string window;
  std::string token;
  std::string tokenFile;
  std::string serverKeyFile;
  std::string codec = "snappy";
  bool wait = false;
};

class Session {
 public:
  // Collective over `comm` (not freed, not kept: the session duplicates what it needs). Throws
  // std::runtime_error (on every rank) for a bad layout, a rank count the layout does not fit,
  // a capture folder that cannot be written, or MPI without MPI_THREAD_MULTIPLE; InputError for
  // MPI_COMM_NULL (on the ranks that gave it).
  Session(MPI_Comm comm, const SessionOptions& options);
  // Not collective: without close() before, the session leaves (see "Leaving" above).
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  bool isWallRank() const;
  MPI_Comm renderComm() const;  // the render ranks; MPI_COMM_NULL on wall ranks
  int canvasWidth() const;
  int canvasHeight() const;

  // Wall ranks: presents frames until the render ranks close the session, then returns.
  void runWall();

  // Render ranks.
  void setStyle(const Style& style);
  // Copies the brick's data (all but borrowed voxels: VolumePart). Data that does not fit the
  // style is refused at the next renderFrame(), on every rank (InputError); a logic_error before
  // setStyle().
  void addBrick(const Brick& brick);
  // The program changed the values of borrowed voxels: the next renderFrame() (on every rank,
  // as for a new scene version) takes the value ranges again, rebuilds the macrocells and
  // isosurfaces of this rank's bricks, and starts the accumulation afresh. Local, like addBrick.
  void dataChanged();
  // A binding's own check of the program's input that failed (a numpy array of a type no voxel
  // type is): refused like a brick that does not fit, by the next renderFrame() on every rank.
  void refuseInput(const std::string& why);
  void clearBricks();
  void setCamera(const Camera& camera);  // render rank 0's camera is the one used
  void renderFrame();
  std::uint32_t framesRendered() const;
  // Render rank 0 without a wall: the last frame, RGBA8, rows top to bottom (elsewhere: empty).
  std::vector<std::uint8_t> image() const;
  // Render rank 0 without a wall: writes the last frame as a PNG (atomically); elsewhere nothing.
  void writeImage(const std::string& path) const;
  // The bytes of brick data this rank holds in the current scene version (its bricks' copied
  // voxels, particles and triangles, and what it built from them; borrowed voxels not counted).
  std::size_t sceneBytes() const;
  // The bytes of borrowed voxels this rank reads in place in the current scene version.
  std::size_t borrowedBytes() const;
  // Render ranks: ends the wall's run after the last frame (waiting until it is presented and
  // captured) and releases the session's communicators. Collective over the whole `comm`
  // together with runWall() returning on the wall ranks.
  void close();

 protected:
  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace dfbwall
